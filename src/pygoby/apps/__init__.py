"""The Goby MOOS applications, one module per console script (thin wiring of the libraries)."""

__all__ = ["ifrontseat", "inetsimmanager", "pacommshandler", "ptranslator", "usimvehicle"]
