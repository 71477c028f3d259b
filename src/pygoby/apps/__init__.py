"""pygoby.apps"""
