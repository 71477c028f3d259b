"""The Goby MOOS applications, one module per console script (thin wiring of the libraries)."""

__all__ = [
    "icommander",
    "ifrontseat",
    "inetsimmanager",
    "liaison",
    "pacommshandler",
    "ptranslator",
    "topside_cli",
    "usimvehicle",
]
