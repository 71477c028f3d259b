"""Modem drivers (all derive from pygoby.acomms.driver_base.ModemDriverBase)."""
