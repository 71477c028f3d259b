"""MOOS <-> protobuf translator (goby3 MOOSTranslator), usable without MOOS.

    from pygoby.moos.translator import Translator, TranslatorRunner, MoosValues, entry_class

    translator = Translator(entries, loader.message_class,          # TranslatorEntry messages
                            lat_origin=42.35, lon_origin=-70.95,     # UTM datum (0, 0 if unset)
                            modem_ids=ModemIdLookup.from_file(path)) # or None
    msg = translator.create("pkg.Msg", {"NAV_X": 550.0, "NAME": "unicorn"})  # TranslatorError
    posts = translator.publish(msg)  # [Post(var, value: float | str | bytes, source_aux)]

* MOOS values are float (double), str (string) or bytes (binary string); a Post with a float
  value is a MOOS double, bytes a binary string. Posts are sorted by variable name.
* Entry problems goby3 would crash on (unknown type, a FORMAT that cannot work, duplicates)
  raise TranslatorConfigError when the Translator is built; what goby3 runs but looks like a
  mistake (an unknown algorithm, a publish directive naming no field) is returned by
  add_entry() as EntryNote(field, message) for the app to log once. Bad data raises
  TranslatorError from create()/publish() and nothing partial is returned, except a FORMAT
  input matching part of its format, which fills what it can as goby3 does and is reported in
  create()'s `mismatches` list (`strict_format: true` on the entry: TranslatorError). Warnings
  (unknown keys, unknown enum values) go to the "pygoby.moos.translator" logger.
* TranslatorRunner(translator, start_time, multiplex_vars, variables=MoosValues(app.dynamic_vars),
  clock=app.clock) is the trigger logic: subscriptions(), on_mail(var, value, stale=) and
  tick(now) return the created messages (partial FORMAT matches: one warning per create rule
  per minute of `clock`); on_multiplex(value, technique) returns inverse-publish posts.
* serialize_for_moos / parse_for_moos / post_for_moos: app-internal messages (default
  `@PB[type] text`); moos_technique_from_config(common) picks the technique.
"""

from pygoby.moos.translator.algorithms import AlgorithmRegistry, render_double
from pygoby.moos.translator.errors import (
    TranslatorConfigError,
    TranslatorError,
    UnconvertibleError,
)
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
from pygoby.protobuf.goby.moos.protobuf.translator_pb2 import TranslatorEntry
from pygoby.util.geodesy import UTMGeodesy
from pygoby.util.modem_id import ModemIdLookup


def entry_class() -> type[TranslatorEntry]:
    """The goby.moos.protobuf.TranslatorEntry message class."""
    return TranslatorEntry


__all__ = [
    "LAT_ORIGIN_VAR",
    "LONG_ORIGIN_VAR",
    "MAGIC_PROTOBUF_HEADER",
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
    "UnconvertibleError",
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
