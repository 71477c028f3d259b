"""Read a Goby 1.1 `<message_set>` file into the model.

The XML goes through a real parser (expat, hardened by defusedxml: no entity expansion, no
external references), then every element is checked against the message schema Goby 1.1
validated with (tags, where they may appear, how often, their attributes and values). Every
problem is a `ConfigError` whose text starts with `file:line:`.
"""

from __future__ import annotations

import logging
import math
import os
import re
import xml.sax
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path

import defusedxml
import defusedxml.sax

from pygoby.dccl.xml.model import (
    FIRST_LAYOUT_FIELD,
    HEADER_ID_MAX,
    HEADER_PARTS,
    MAX_DCCL_ID,
    V1_PLACEHOLDER,
    Publish,
    PublishVar,
    Queuing,
    Var,
    XmlMessage,
)
from pygoby.errors import ConfigError

log = logging.getLogger(__name__)

IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
# An XML file is configuration: anything larger is a mistake (and must not eat the memory).
MAX_FILE_BYTES = 16 * 1024 * 1024

# Goby 1.1 algorithm names and those Goby 2 added; `alg_TSD_to_soundspeed`
# is the manual's spelling of the code's TSD_to_soundspeed.
ALGORITHM_ALIASES = {"alg_TSD_to_soundspeed": "TSD_to_soundspeed"}
ALGORITHMS = frozenset(
    {
        "to_upper",
        "to_lower",
        "angle_0_360",
        "angle_-180_180",
        "lon2utm_x",
        "lat2utm_y",
        "utm_x2lon",
        "utm_y2lat",
        "modem_id2name",
        "name2modem_id",
        "modem_id2type",
        "power_to_dB",
        "dB_to_power",
        "TSD_to_soundspeed",
        "add",
        "subtract",
        "abs",
        "lat2hemisphere_initial",
        "lon2hemisphere_initial",
        "lat2nmea_lat",
        "lon2nmea_lon",
        "unix_time2nmea_time",
    }
)
# Reference-taking algorithms and how many references each needs.
ALGORITHM_REFERENCES = {
    "lon2utm_x": 1,
    "lat2utm_y": 1,
    "utm_x2lon": 1,
    "utm_y2lat": 1,
    "TSD_to_soundspeed": 2,
    "add": 1,
    "subtract": 1,
}


# ---------------------------------------------------------------------------------------------
# The element tree, with line numbers


@dataclass
class Element:
    tag: str
    attrs: dict[str, str]
    line: int
    children: list[Element] = field(default_factory=list)
    text: str = ""


class _TreeBuilder(xml.sax.ContentHandler):
    def __init__(self) -> None:
        super().__init__()
        self.locator = None
        self.stack: list[Element] = []
        self.root: Element | None = None

    def setDocumentLocator(self, locator) -> None:  # noqa: N802 - SAX API
        self.locator = locator

    def line(self) -> int:
        return self.locator.getLineNumber() if self.locator is not None else 0

    def startElement(self, name, attrs) -> None:  # noqa: N802 - SAX API
        element = Element(name, dict(attrs.items()), self.line())
        if self.stack:
            self.stack[-1].children.append(element)
        else:
            self.root = element
        self.stack.append(element)

    def endElement(self, name) -> None:  # noqa: N802 - SAX API
        self.stack.pop()

    def characters(self, content) -> None:
        if self.stack:
            self.stack[-1].text += content


def parse_tree(data: bytes, file: Path) -> Element:
    """The document's root element; malformed XML is a ConfigError at its line."""
    builder = _TreeBuilder()
    try:
        defusedxml.sax.parseString(
            data, builder, forbid_dtd=False, forbid_entities=True, forbid_external=True
        )
    except xml.sax.SAXParseException as err:
        reason = err.getMessage()
        if "mismatched tag" in reason and builder.stack:
            open_element = builder.stack[-1]
            reason += f" (<{open_element.tag}> of line {open_element.line} is not closed)"
        raise ConfigError(reason, file=file, line=err.getLineNumber()) from None
    except defusedxml.DefusedXmlException as err:
        raise ConfigError(
            f"not allowed in a message set: {err}", file=file, line=builder.line()
        ) from None
    except (xml.sax.SAXException, LookupError, ValueError) as err:  # e.g. an unknown encoding
        raise ConfigError(
            f"cannot read the XML: {err}", file=file, line=builder.line() or 1
        ) from None
    assert builder.root is not None
    return builder.root


# ---------------------------------------------------------------------------------------------
# The schema Goby 1.1 validated against (goby/xml/message_schema.xsd): per element, its allowed
# children with (minimum, maximum) occurrences and its allowed attributes. `None` maximum: any.

_SOURCE = {"src_var": (0, 1), "moos_var": (0, 1)}
Occurs = dict[str, tuple[int, int | None]]  # child tag -> (min, max) occurrences
_HEADER_PIECE: Occurs = {"name": (1, 1), **_SOURCE}
_VAR_COMMON: Occurs = {"name": (1, 1), **_SOURCE, "array_length": (0, 1)}
SCHEMA: dict[str, tuple[Occurs, frozenset[str]]] = {
    "message_set": ({"message": (1, None)}, frozenset()),
    "message": (
        {
            "name": (1, 1),
            "id": (0, 1),
            "repeat": (0, 1),
            "destination_var": (0, 1),
            "destination_moos_var": (0, 1),
            "size": (1, 1),
            "outgoing_hex_moos_var": (0, 1),
            "incoming_hex_moos_var": (0, 1),
            "trigger": (0, 1),
            "trigger_time": (0, 1),
            "trigger_var": (0, 1),
            "trigger_moos_var": (0, 1),
            "header": (0, 1),
            "layout": (1, 1),
            "on_receipt": (0, 1),
            "queuing": (0, 1),
        },
        frozenset(),
    ),
    "header": ({"id": (0, 1), "time": (0, 1), "src_id": (0, 1), "dest_id": (0, 1)}, frozenset()),
    "time": (_HEADER_PIECE, frozenset({"algorithm"})),
    "src_id": (_HEADER_PIECE, frozenset({"algorithm"})),
    "dest_id": (_HEADER_PIECE, frozenset({"algorithm"})),
    "layout": (
        dict.fromkeys(("static", "int", "bool", "float", "string", "hex", "enum"), (0, None)),
        frozenset(),
    ),
    "static": ({"name": (1, 1), "value": (1, 1)}, frozenset({"algorithm"})),
    "int": (
        {**_VAR_COMMON, "max": (1, 1), "min": (1, 1), "max_delta": (0, 1)},
        frozenset({"algorithm"}),
    ),
    "bool": (_VAR_COMMON, frozenset({"algorithm"})),
    "float": (
        {**_VAR_COMMON, "max": (1, 1), "min": (1, 1), "precision": (1, 1), "max_delta": (0, 1)},
        frozenset({"algorithm"}),
    ),
    "string": ({**_VAR_COMMON, "max_length": (1, 1)}, frozenset({"algorithm"})),
    "hex": ({**_VAR_COMMON, "num_bytes": (1, 1)}, frozenset({"algorithm"})),
    "enum": ({**_VAR_COMMON, "value": (1, None)}, frozenset({"algorithm"})),
    "on_receipt": ({"publish": (1, None)}, frozenset()),
    "publish": (
        {
            "format": (0, 1),
            "publish_var": (0, 1),
            "moos_var": (0, 1),
            "message_var": (0, None),
            "all": (0, 1),
        },
        frozenset(),
    ),
    "queuing": (
        dict.fromkeys(
            (
                "ack",
                "blackout_time",
                "max_queue",
                "value_base",
                "ttl",
                "newest_first",
                "priority_base",
                "priority_time_const",
            ),
            (0, 1),
        ),
        frozenset(),
    ),
}
# Leaf elements (text only) and their attributes.
LEAF_ATTRIBUTES = {
    "src_var": frozenset({"key"}),
    "moos_var": frozenset({"key", "type"}),
    "trigger_var": frozenset({"mandatory_content"}),
    "trigger_moos_var": frozenset({"mandatory_content"}),
    "destination_var": frozenset({"key"}),
    "destination_moos_var": frozenset({"key"}),
    "publish_var": frozenset({"type"}),
    "message_var": frozenset({"algorithm"}),
}
EMPTY_ELEMENTS = frozenset({"repeat", "all"})
# Aliases: the second spelling means the first (both in one element is an error).
ALIASES = {
    "moos_var": "src_var",
    "trigger_moos_var": "trigger_var",
    "destination_moos_var": "destination_var",
}
PUBLISH_TYPES = frozenset({"double", "string", "long", "bool"})


class _Reader:
    """Turns the element tree into `XmlMessage`s, raising ConfigError at the first problem and
    collecting warnings (deprecated tags Goby 2 ignored as well)."""

    def __init__(self, file: Path) -> None:
        self.file = file
        self.warnings: list[str] = []

    # -- helpers -------------------------------------------------------------------------------
    def error(self, line: int, reason: str) -> ConfigError:
        return ConfigError(reason, file=self.file, line=line)

    def warn(self, line: int, reason: str) -> None:
        text = f"{self.file}:{line}: {reason}"
        self.warnings.append(text)
        log.warning("%s", text)

    def check_structure(self, element: Element, context: str) -> dict[str, list[Element]]:
        """Children grouped by tag, after checking tags, counts, attributes and stray text."""
        allowed, attributes = SCHEMA[element.tag]
        self.check_attributes(element, attributes)
        if element.text.strip():
            raise self.error(
                element.line,
                f"<{element.tag}> holds text {element.text.strip()!r}; it may only contain tags",
            )
        groups: dict[str, list[Element]] = {}
        for child in element.children:
            if child.tag not in allowed:
                where = f"<{element.tag}>" + (f" of {context}" if context else "")
                raise self.error(
                    child.line,
                    f"unknown tag <{child.tag}> in {where} (allowed: {', '.join(sorted(allowed))})",
                )
            groups.setdefault(child.tag, []).append(child)
            if child.tag in SCHEMA:
                continue
            self.check_attributes(child, LEAF_ATTRIBUTES.get(child.tag, frozenset()))
            if child.children:
                raise self.error(
                    child.children[0].line,
                    f"<{child.tag}> holds text only, not <{child.children[0].tag}>",
                )
            if child.tag in EMPTY_ELEMENTS and child.text.strip():
                raise self.error(child.line, f"<{child.tag}/> takes no content")
        for tag, (low, high) in allowed.items():
            found = groups.get(tag, [])
            if len(found) < low:
                raise self.error(element.line, f"<{element.tag}> needs <{tag}>")
            if high is not None and len(found) > high:
                raise self.error(
                    found[high].line, f"<{tag}> given more than once in <{element.tag}>"
                )
        for alias, canonical in ALIASES.items():
            if alias in groups and canonical in groups:
                raise self.error(
                    groups[alias][0].line, f"<{alias}> and <{canonical}> mean the same; give one"
                )
        return groups

    def check_attributes(self, element: Element, allowed: frozenset[str]) -> None:
        for name in element.attrs:
            if name not in allowed:
                hint = f" (allowed: {', '.join(sorted(allowed))})" if allowed else ""
                raise self.error(
                    element.line, f"unknown attribute {name!r} on <{element.tag}>{hint}"
                )

    def text(self, element: Element, what: str = "") -> str:
        value = element.text.strip()
        if not value:
            raise self.error(element.line, f"<{element.tag}> is empty{what}")
        return value

    def integer(self, element: Element, low: int | None = None, high: int | None = None) -> int:
        text = self.text(element)
        if not re.fullmatch(r"[+-]?[0-9]+", text):
            raise self.error(element.line, f"<{element.tag}> must be an integer, not {text!r}")
        value = int(text)
        if (low is not None and value < low) or (high is not None and value > high):
            bounds = f"{low}..{high}" if high is not None else f">= {low}"
            raise self.error(element.line, f"<{element.tag}> {value} is out of range ({bounds})")
        return value

    def number(self, element: Element) -> float:
        text = self.text(element)
        try:
            value = float(text)
        except ValueError:
            raise self.error(
                element.line, f"<{element.tag}> must be a number, not {text!r}"
            ) from None
        if not math.isfinite(value):
            raise self.error(element.line, f"<{element.tag}> must be a finite number, not {text!r}")
        return value

    def boolean(self, element: Element) -> bool:
        text = self.text(element).lower()
        if text in ("true", "1"):
            return True
        if text in ("false", "0"):
            return False
        raise self.error(
            element.line, f"<{element.tag}> must be true or false, not {element.text.strip()!r}"
        )

    def identifier(self, element: Element, what: str) -> str:
        text = self.text(element)
        if not IDENTIFIER.fullmatch(text):
            raise self.error(
                element.line,
                f"{what} {text!r} is not a valid name (letters, digits "
                "and _, not starting with a digit)",
            )
        return text

    def algorithms(self, element: Element) -> list[str]:
        raw = element.attrs.get("algorithm")
        if raw is None:
            return []
        names = [a for a in raw.replace(" ", "").split(",") if a]
        if not names:
            raise self.error(element.line, f"<{element.tag}> has an empty algorithm attribute")
        out = []
        for spec in names:
            name, *references = spec.split(":")
            name = ALGORITHM_ALIASES.get(name, name)
            if name not in ALGORITHMS:
                raise self.error(
                    element.line,
                    f"unknown algorithm {name!r} (known: {', '.join(sorted(ALGORITHMS))})",
                )
            if any(not r for r in references):
                raise self.error(element.line, f"algorithm {spec!r} has an empty reference")
            needed = ALGORITHM_REFERENCES.get(name, 0)
            if len(references) < needed:
                raise self.error(
                    element.line,
                    f"algorithm {name!r} needs {needed} reference variable(s) ({name}:other_var)",
                )
            out.append(":".join([name, *references]))
        return out

    # -- document ------------------------------------------------------------------------------
    def read(self, root: Element) -> list[XmlMessage]:
        if root.tag != "message_set":
            raise self.error(root.line, f"the root element must be <message_set>, not <{root.tag}>")
        groups = self.check_structure(root, "")
        messages = [self.message(e) for e in groups["message"]]
        seen_ids: dict[int, XmlMessage] = {}
        seen_names: dict[str, XmlMessage] = {}
        for msg in messages:
            assert msg.id is not None
            if msg.id in seen_ids:
                raise self.error(
                    msg.line,
                    f"duplicate id {msg.id}: {msg.name} and "
                    f"{seen_ids[msg.id].name} (line {seen_ids[msg.id].line})",
                )
            if msg.name in seen_names:
                raise self.error(
                    msg.line,
                    f"duplicate message name {msg.name!r} (first at line "
                    f"{seen_names[msg.name].line})",
                )
            seen_ids[msg.id] = msg
            seen_names[msg.name] = msg
        return messages

    def message(self, element: Element) -> XmlMessage:
        groups = self.check_structure(element, "")
        msg = XmlMessage(self.file, element.line)
        msg.name = self.identifier(groups["name"][0], "message name")
        context = f"message {msg.name}"
        msg.size = self.integer(groups["size"][0], 1, 65535)
        if "repeat" in groups:
            msg.repeat = True
            self.warn(
                groups["repeat"][0].line,
                "<repeat/> is deprecated and ignored in the Goby 2 form (as in Goby 2): "
                "post the message several times instead (DCCL1, the Goby 1.1 form, honours it)",
            )
        self.trigger(msg, groups)
        header_groups = (
            self.check_structure(groups["header"][0], context) if "header" in groups else {}
        )
        ids = list(groups.get("id", []) + header_groups.get("id", []))
        if not ids:
            raise self.error(element.line, f"{context} needs an <id> (in <message> or <header>)")
        if len(ids) > 1:
            raise self.error(ids[1].line, f"{context} has an <id> in both <message> and <header>")
        msg.id = self.integer(ids[0], 0, MAX_DCCL_ID)
        for tag, (number, default_name) in HEADER_PARTS.items():
            piece = Var(tag, default_name, element.line, number=number, max=HEADER_ID_MAX, min=0)
            if tag in header_groups:
                piece = self.header_piece(header_groups[tag][0], tag, number, context)
            msg.header[tag] = piece
        destination = groups.get("destination_var", []) + groups.get("destination_moos_var", [])
        if destination:
            self.legacy_destination(msg, destination[0], "dest_id" in header_groups)
        layout = groups["layout"][0]
        self.check_structure(layout, context)
        if not layout.children:
            raise self.error(layout.line, f"<layout> of {context} needs at least one variable")
        for number, child in enumerate(layout.children, start=FIRST_LAYOUT_FIELD):
            msg.layout.append(self.layout_var(child, number, context))
        self.check_names(msg)
        for var in msg.all_vars():
            self.default_source(msg, var)
            self.check_algorithm_references(
                msg, var.algorithms, var.line, create_side=True, var=var
            )
        if "on_receipt" in groups:
            receipt = groups["on_receipt"][0]
            receipt_groups = self.check_structure(receipt, context)
            msg.publishes = [self.publish(p, msg) for p in receipt_groups["publish"]]
        if "queuing" in groups:
            msg.queuing = self.queuing(groups["queuing"][0], context)
        # the variables the encoded message is posted on (Goby 1.1 configurations only)
        if "incoming_hex_moos_var" in groups:
            msg.incoming_hex_var = self.text(groups["incoming_hex_moos_var"][0])
        if "outgoing_hex_moos_var" in groups:
            msg.outgoing_hex_var = self.text(groups["outgoing_hex_moos_var"][0])
        return msg

    def ignored(
        self,
        groups: dict[str, list[Element]],
        tags: Iterable[str],
        check: Callable[[Element], object],
        reason: str,
    ) -> None:
        """Tags read (their value checked) and ignored, with a warning."""
        for tag in tags:
            if tag in groups:
                check(groups[tag][0])
                self.warn(groups[tag][0].line, f"<{tag}> {reason}")

    def trigger(self, msg: XmlMessage, groups: dict[str, list[Element]]) -> None:
        trigger_elements = groups.get("trigger_var", []) + groups.get("trigger_moos_var", [])
        if "trigger" in groups:
            msg.trigger = self.text(groups["trigger"][0]).lower()
            if msg.trigger not in ("publish", "time"):
                raise self.error(
                    groups["trigger"][0].line,
                    f"<trigger> must be 'publish' or 'time', not {msg.trigger!r}",
                )
        if trigger_elements:
            element = trigger_elements[0]
            if msg.trigger != "publish":
                raise self.error(element.line, f"<{element.tag}> needs <trigger>publish</trigger>")
            msg.trigger_var = self.text(element)
            msg.mandatory_content = element.attrs.get("mandatory_content", "")
        if "trigger_time" in groups:
            element = groups["trigger_time"][0]
            if msg.trigger != "time":
                raise self.error(element.line, "<trigger_time> needs <trigger>time</trigger>")
            msg.trigger_time = self.integer(element, 1, 2**32 - 1)
        if msg.trigger == "publish" and not msg.trigger_var:
            raise self.error(
                groups["trigger"][0].line, "<trigger>publish</trigger> needs <trigger_var>"
            )
        if msg.trigger == "time" and msg.trigger_time is None:
            raise self.error(
                groups["trigger"][0].line, "<trigger>time</trigger> needs <trigger_time>"
            )

    def source(self, var: Var, groups: dict[str, list[Element]]) -> None:
        found = groups.get("src_var", []) + groups.get("moos_var", [])
        if not found:
            return
        element = found[0]
        var.source_var = self.text(element)
        var.source_set = True
        if "type" in element.attrs:
            raise self.error(
                element.line, f"attribute 'type' belongs to a <publish>'s <{element.tag}>"
            )
        if "key" in element.attrs:
            self.warn(
                element.line,
                f"<{element.tag} key=...> is ignored (as in Goby 2): the value "
                "is read by the variable's name",
            )

    def header_piece(self, element: Element, tag: str, number: int, context: str) -> Var:
        groups = self.check_structure(element, context)
        name = self.identifier(groups["name"][0], f"<{tag}> name")
        piece = Var(tag, name, element.line, number=number, algorithms=self.algorithms(element))
        if tag != "time":
            piece.max, piece.min = HEADER_ID_MAX, 0
        self.source(piece, groups)
        return piece

    def legacy_destination(self, msg: XmlMessage, element: Element, has_dest: bool) -> None:
        if has_dest:
            raise self.error(
                element.line, f"<{element.tag}> and <header><dest_id> both set the destination"
            )
        piece = msg.header["dest_id"]
        key = element.attrs.get("key")
        if key is not None:
            if not IDENTIFIER.fullmatch(key):
                raise self.error(element.line, f"destination key {key!r} is not a valid name")
            piece.name = key
        piece.line = element.line
        piece.source_var = self.text(element)
        piece.source_set = True

    def layout_var(self, element: Element, number: int, context: str) -> Var:
        groups = self.check_structure(element, context)
        kind = element.tag
        var = Var(
            kind,
            self.identifier(groups["name"][0], f"<{kind}> name"),
            element.line,
            number=number,
            algorithms=self.algorithms(element),
        )
        self.source(var, groups)
        if "array_length" in groups:
            var.array_length = self.integer(groups["array_length"][0], 1, 1_000_000)
        if "max_delta" in groups:
            var.max_delta = abs(self.number(groups["max_delta"][0]))
            self.warn(
                groups["max_delta"][0].line,
                "<max_delta> (delta encoding) is ignored in the Goby 2 form, as in Goby 2: the "
                "value is sent in full (DCCL1, the Goby 1.1 form, honours it)",
            )
        if kind == "static":
            var.static_value = self.text(groups["value"][0])
            if len(var.static_value.split()) != 1:
                raise self.error(
                    groups["value"][0].line,
                    f"static value {var.static_value!r} must be one word (DCCL "
                    "decodes a static value up to its first space)",
                )
        elif kind == "int":
            var.max, var.min = (
                self.integer(groups[k][0], -(2**31), 2**31 - 1) for k in ("max", "min")
            )
        elif kind == "float":
            var.max, var.min = (self.number(groups[k][0]) for k in ("max", "min"))
            var.precision = self.integer(groups["precision"][0], -15, 15)
        elif kind == "string":
            var.max_length = self.integer(groups["max_length"][0], 1, 255)
        elif kind == "hex":
            var.num_bytes = self.integer(groups["num_bytes"][0], 1, 255)
        elif kind == "enum":
            for value in groups["value"]:
                text = self.text(value)
                if not re.fullmatch(r"[A-Za-z0-9_]+", text):
                    raise self.error(
                        value.line, f"enum value {text!r} may only hold letters, digits and _"
                    )
                if text in var.enum_values:
                    raise self.error(value.line, f"enum value {text!r} given twice")
                var.enum_values.append(text)
        if var.max is not None and var.min is not None and var.max < var.min:
            var.max, var.min = var.min, var.max  # Goby 1.1 swaps them
            self.warn(
                element.line, f"{kind} {var.name}: <max> is below <min>; swapped (as Goby 1.1)"
            )
        return var

    def check_names(self, msg: XmlMessage) -> None:
        seen: dict[str, Var] = {}
        for var in sorted(msg.all_vars(), key=lambda v: v.line):
            if var.name in seen:
                raise self.error(
                    var.line,
                    f"variable name {var.name!r} is used twice in message "
                    f"{msg.name} (first at line {seen[var.name].line})",
                )
            seen[var.name] = var

    def default_source(self, msg: XmlMessage, var: Var) -> None:
        """Goby 1.1: a variable without <src_var> reads the trigger variable; a header piece
        left with its default name reads nothing (it is filled by pAcommsHandler)."""
        if var.source_set:
            return
        if var.is_header and not var.named:
            var.source_var = ""
        else:
            var.source_var = msg.trigger_var

    def check_algorithm_references(
        self,
        msg: XmlMessage,
        algorithms: Iterable[str],
        line: int,
        create_side: bool,
        var: Var | None = None,
    ) -> None:
        for spec in algorithms:
            name, *references = spec.split(":")
            for reference in references:
                if msg.var(reference) is None:
                    raise self.error(
                        line,
                        f"algorithm {name!r} refers to {reference!r}, which is "
                        f"not a variable of message {msg.name}",
                    )
            if create_side and references:
                # Goby 2's rule, kept (upstream indexes an empty list instead: QUIRKS.md Q-APPS-13):
                # the translator runs create-side algorithms on one field's text, before the
                # other fields exist, so an algorithm with references is refused at load
                raise self.error(
                    line,
                    f"algorithm {spec!r} on {var.name if var else '?'}: "
                    "algorithms with reference variables are only allowed in "
                    "<publish> (<message_var algorithm=...>)",
                )
            if create_side and var is not None and not var.source_var:
                raise self.error(
                    line,
                    f"algorithm {name!r} on {var.name}: the variable has no "
                    "<src_var> (nor a trigger variable) to read",
                )

    def publish(self, element: Element, msg: XmlMessage) -> Publish:
        groups = self.check_structure(element, f"message {msg.name}")
        out = Publish(element.line)
        variables = groups.get("publish_var", []) + groups.get("moos_var", [])
        if not variables:
            raise self.error(element.line, "<publish> needs <publish_var> (or <moos_var>)")
        target = variables[0]
        out.moos_var = self.text(target)
        kind = target.attrs.get("type")
        if kind is not None and kind not in PUBLISH_TYPES:
            raise self.error(
                target.line, f"type {kind!r} must be one of {', '.join(sorted(PUBLISH_TYPES))}"
            )
        if "key" in target.attrs:
            raise self.error(
                target.line, f"attribute 'key' is not allowed on a <publish>'s <{target.tag}>"
            )
        if "format" in groups:
            out.format = groups["format"][0].text.strip()
        for value in groups.get("message_var", []):
            name = self.text(value)
            if msg.var(name) is None:
                raise self.error(
                    value.line, f"<message_var> {name!r} is not a variable of message {msg.name}"
                )
            algorithms = self.algorithms(value)
            self.check_algorithm_references(msg, algorithms, value.line, create_side=False)
            out.values.append(PublishVar(name, algorithms, value.line))
        if "all" in groups:
            out.all = True
            listed = {v.name for v in out.values}
            for var in msg.all_vars():
                if (not var.is_header or var.named) and var.name not in listed:
                    out.values.append(PublishVar(var.name, [], groups["all"][0].line))
        if not out.values:
            raise self.error(
                element.line, "<publish> has nothing to publish: give <message_var>s or <all/>"
            )
        count = sum(var.array_length for var in (msg.var(v.name) for v in out.values) if var)
        checked = [(target, out.moos_var)]
        if out.format is not None:
            checked.append((groups["format"][0], out.format))
        for holder, text in checked:
            for match in V1_PLACEHOLDER.finditer(text):
                k = int(match.group(1))
                if not 1 <= k <= count:
                    raise self.error(
                        holder.line,
                        f"<{holder.tag}> uses %{k}, but the <publish> "
                        f"has {count} value(s) (%1 to %{count})",
                    )
        return out

    def queuing(self, element: Element, context: str) -> Queuing:
        groups = self.check_structure(element, context)
        q = Queuing()
        readers: dict[str, Callable[[Element], object]] = {
            "ack": self.boolean,
            "newest_first": self.boolean,
            "blackout_time": lambda e: self.integer(e, 0, 2**32 - 1),
            "max_queue": lambda e: self.integer(e, 0, 2**32 - 1),
            "value_base": self.number,
            "ttl": lambda e: self.integer(e, 0, 2**31 - 1),
        }
        for tag, read in readers.items():
            if tag in groups:
                setattr(q, tag, read(groups[tag][0]))
        self.ignored(
            groups,
            ("priority_base", "priority_time_const"),
            self.number,
            "is deprecated and ignored (as in Goby 1.1); use <value_base> and <ttl>",
        )
        return q


def read_message_set(
    data: bytes, file: str | os.PathLike[str] = "<xml>"
) -> tuple[list[XmlMessage], list[str]]:
    """Parse and check the XML text of a message set: (messages, warnings)."""
    path = Path(file)
    reader = _Reader(path)
    return reader.read(parse_tree(data, path)), reader.warnings


def read_message_file(path: str | os.PathLike[str]) -> tuple[list[XmlMessage], list[str]]:
    p = Path(path)
    try:
        with open(p, "rb") as handle:
            data = handle.read(MAX_FILE_BYTES + 1)
    except OSError as err:
        raise ConfigError(f"cannot read the XML message file: {err.strerror}", file=p) from None
    if len(data) > MAX_FILE_BYTES:
        raise ConfigError(f"larger than {MAX_FILE_BYTES} bytes; not a message set", file=p)
    return read_message_set(data, p)
