"""MOOS <-> protobuf translator (goby3 MOOSTranslator), usable without MOOS.

from pygoby.moos.translator import Translator, TranslatorRunner, entry_class
translator = Translator(entries, loader.message_class, lat_origin=42.35, lon_origin=-70.95)
msg = translator.create("pkg.Msg", {"NAV_X": 550.0, "NAME": "unicorn"})
posts = translator.publish(msg)   # [Post(var, value: str | float | bytes, source_aux)]
"""

from pygoby.moos.translator.algorithms import AlgorithmRegistry, render_double
from pygoby.moos.translator.errors import TranslatorConfigError, TranslatorError
from pygoby.moos.translator.geodesy import UTMGeodesy
from pygoby.moos.translator.modem_id import ModemIdLookup
from pygoby.moos.translator.techniques import (
    MAGIC_PROTOBUF_HEADER,
    MoosValue,
    Technique,
    dynamic_parse,
    moos_technique_from_config,
    parse_for_moos,
    parse_protobuf,
    serialize_for_moos,
    serialize_protobuf,
)
from pygoby.moos.translator.translator import (
    LAT_ORIGIN_VAR,
    LONG_ORIGIN_VAR,
    MoosValues,
    Post,
    Translator,
    TranslatorRunner,
    make_post,
    post_for_moos,
)

TRANSLATOR_PROTO = "goby/moos/protobuf/translator.proto"


def entry_class():
    """The goby.moos.protobuf.TranslatorEntry message class."""
    from pygoby.protobuf import builtin_class

    return builtin_class(TRANSLATOR_PROTO, "goby.moos.protobuf.TranslatorEntry")


__all__ = [
    "LAT_ORIGIN_VAR",
    "LONG_ORIGIN_VAR",
    "MAGIC_PROTOBUF_HEADER",
    "TRANSLATOR_PROTO",
    "AlgorithmRegistry",
    "ModemIdLookup",
    "MoosValue",
    "MoosValues",
    "Post",
    "Technique",
    "Translator",
    "TranslatorConfigError",
    "TranslatorError",
    "TranslatorRunner",
    "UTMGeodesy",
    "dynamic_parse",
    "entry_class",
    "make_post",
    "moos_technique_from_config",
    "parse_for_moos",
    "parse_protobuf",
    "post_for_moos",
    "render_double",
    "serialize_for_moos",
    "serialize_protobuf",
]
