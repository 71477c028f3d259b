"""What a simulation leaves behind: its event log (`eventlog`) and the plots of it (`plots`,
`pygoby netsim report`).
"""

__all__ = [
    "eventlog",
    "plots",
]
