"""pygoby.moos"""
