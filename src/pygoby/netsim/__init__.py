"""pygoby.netsim"""
