"""Pieces of Goby 1.1 pAcommsHandler mission files the goby11 tests share."""

from __future__ import annotations


def micromodem_driver_goby11(modem_port: int) -> str:
    """Goby 1.1's driver_type and driver_cfg for a Micro-Modem emulator on 127.0.0.1:modem_port
    (its NVRAM kept: the emulator starts with the defaults the tests expect)."""
    return f"""\
  driver_type: DRIVER_WHOI_MICROMODEM
  driver_cfg
  {{
    connection_type: CONNECTION_TCP_AS_CLIENT
    tcp_server: "127.0.0.1"
    tcp_port: {modem_port}
    [MicroModemConfig.reset_nvram]: false
  }}"""
