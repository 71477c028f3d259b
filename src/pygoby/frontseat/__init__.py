"""pygoby.frontseat"""
