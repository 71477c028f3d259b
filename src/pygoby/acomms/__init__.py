"""pygoby.acomms"""
