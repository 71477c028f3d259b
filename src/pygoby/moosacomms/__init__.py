"""pygoby.moosacomms: goby-acomms on MOOS (what goby3's src/moos holds).

Above `acomms` and `moos`, below `topside` and `apps`: the pieces pAcommsHandler, pTranslator,
pREMUSCodec and the topside tools share.

* `acomms_config`: reading pAcommsHandler's configuration and the message set it loads.
* `translator_binding`: a `Translator` bound to a MOOS app (pTranslator, pAcommsHandler).
* `transitional`: Goby 1.1 DCCL1 XML message sets converted for the Goby 2 translator.
* `goby11`: pAcommsHandler's Goby 1.1 MOOS variables (status, MAC updates, CCL queues).
* `ufield_link`: a Micro-Modem link over uField MOOS mail.
* `remus_reports`: pREMUSCodec's translation of REMUS CCL reports to and from MOOS variables.
* `alog_decode`, `alog_series`, `alog_plots`: a mission's acomms and translator variables in .alog
  files, decoded into columns (`pygoby log convert --mission`) and plotted (`pygoby log plot`).
"""

from pygoby.util.modules import lazy_exports

# imported on first use: each pulls in protobuf, DCCL and the MOOS client as it needs
__getattr__, __dir__ = lazy_exports(
    globals(),
    {
        "AcommsMessageSet": "pygoby.moosacomms.acomms_config",
        "Goby11Variables": "pygoby.moosacomms.goby11",
        "MOOSMailLink": "pygoby.moosacomms.ufield_link",
        "MessageTypes": "pygoby.moosacomms.translator_binding",
        "RemusReports": "pygoby.moosacomms.remus_reports",
        "TransitionalMessages": "pygoby.moosacomms.transitional",
        "TranslatorBinding": "pygoby.moosacomms.translator_binding",
        "read_acomms_config": "pygoby.moosacomms.acomms_config",
    },
)

__all__ = [
    "AcommsMessageSet",
    "Goby11Variables",
    "MOOSMailLink",
    "MessageTypes",
    "RemusReports",
    "TransitionalMessages",
    "TranslatorBinding",
    "read_acomms_config",
]
