"""The Bluefin Standard Payload Interface: sentence codec and a Huxley simulator (sans-I/O core
and TCP server). The iFrontSeat driver is pygoby.frontseat.drivers.bluefin."""
