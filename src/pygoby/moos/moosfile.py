"""`.moos` mission files: globals, ProcessConfig blocks, the ANTLER block
and the Goby TextFormat block.

    mission = MissionFile.read("alpha.moos")
    mission.get_value("ServerPort")          # "9000": first match anywhere, white space removed
    mission.get_value("LatOrigin", outside_blocks=True)   # only lines outside ProcessConfig blocks
    mission.get_float("LatOrigin")           # None unless numeric
    mission.process_config("pHelmIvP")       # [Setting(name, value, line), ...] in file order
    mission.goby_block("pAcommsHandler")     # GobyBlock(text, first_line) for TextFormat parsing
    mission.antler()                         # AntlerConfig with its Run entries
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple

from pygoby.errors import ConfigError
from pygoby.moos.errors import MissionFileError

_NUMERIC = re.compile(r"[0-9.eE+\-]+")
_MACRO_USE = re.compile(r"\$\{([^}]*)\}")


class Setting(NamedTuple):
    """One `name = value` line of a ProcessConfig block; `line` is its file line (1-based),
    for errors that say where (None when the setting did not come from a file)."""

    name: str
    value: str
    line: int | None = None


def strip_comment(line: str) -> str:
    """A line without its `//` comment; the first pair of double quotes protects its content
    (and is removed)."""
    text = line.strip()
    if text.startswith("//"):
        return ""
    first = text.find('"')
    second = text.find('"', first + 1) if first >= 0 else -1
    if second < 0:
        cut = text.find("//")
        return text if cut < 0 else text[:cut]
    before, inside, after = text[:first], text[first + 1 : second], text[second + 1 :]
    cut = before.find("//")
    if cut >= 0:
        return before[:cut]
    cut = after.find("//")
    return before + inside + (after if cut < 0 else after[:cut])


def parse_number(value: str) -> float | None:
    """MOOS's numeric rule: only `0-9 . e E + -` characters, then converted; else None."""
    if not _NUMERIC.fullmatch(value):
        return None
    try:
        return float(value)
    except ValueError:
        return None


def _strip_textformat_comments(line: str) -> str:
    """`//` becomes `#` only outside quoted strings (goby3 replaces every `//`, even in
    quoted strings; fixed: QUIRKS.md Q-APPS-1)."""
    out = []
    quote = ""
    i = 0
    while i < len(line):
        c = line[i]
        if quote:
            if c == "\\":
                out.append(line[i : i + 2])
                i += 2
                continue
            if c == quote:
                quote = ""
        elif c in "\"'":
            quote = c
        elif line.startswith("//", i):
            out.append("#")
            i += 2
            continue
        out.append(c)
        i += 1
    return "".join(out)


def _no_space(text: str) -> str:
    return text.replace(" ", "").replace("\t", "").replace("\r", "")


@dataclass
class GobyBlock:
    """The TextFormat text of a Goby app's block and the file line on which it starts."""

    text: str
    first_line: int  # 1-based line number of the text's first line in the file

    def file_line(self, text_line: int) -> int:
        return self.first_line + text_line - 1


@dataclass
class AntlerRun:
    program: str
    moos_name: str
    options: dict[str, str] = field(default_factory=dict)
    extra_args: list[str] = field(default_factory=list)


@dataclass
class AntlerConfig:
    runs: list[AntlerRun]
    ms_between_launches: float = 1000.0
    executable_path: str | None = None


class MissionFile:
    def __init__(self, raw_lines: list[str], path: Path | None = None) -> None:
        self.path = path
        self.raw_lines = raw_lines
        self.lines = self._preprocess(raw_lines)  # comments removed, macros expanded
        # the same with double quotes kept (MOOS's reader with verbatim quoting disabled)
        self.quoted_lines = self._preprocess(raw_lines, keep_quotes=True)
        self._in_block = self._block_mask(self.lines)

    @classmethod
    def read(cls, path: str | os.PathLike[str]) -> MissionFile:
        p = Path(path)
        return cls(p.read_text(errors="surrogateescape").splitlines(), p)

    @classmethod
    def from_text(cls, text: str) -> MissionFile:
        return cls(text.splitlines())

    def search_dirs(self) -> list[str]:
        """Where relative file names in the mission are looked up: the working directory, then
        the mission file's folder (so that missions can be run from anywhere)."""
        dirs = [str(Path.cwd())]
        if self.path:
            dirs.append(str(Path(self.path).resolve().parent))
        return list(dict.fromkeys(dirs))

    def find_file(self, path: str) -> str:
        """A relative path that does not exist from the working directory is looked up next to
        the mission file; `path` unchanged when it is found in neither."""
        given = Path(path)
        if given.is_absolute() or given.exists() or not self.path:
            return path
        beside = Path(self.path).parent / given
        return str(beside) if beside.exists() else path

    @staticmethod
    def _preprocess(raw_lines: list[str], keep_quotes: bool = False) -> list[str]:
        macros: dict[str, str] = {}

        def expand(match: re.Match[str]) -> str:
            name = match.group(1)
            return macros.get(name, os.environ.get(name, ""))

        out = []
        for raw in raw_lines:
            line = _MACRO_USE.sub(expand, raw[:2000])
            marker = line.find("define:")
            if marker >= 0:
                name, _, value = line[marker + len("define:") :].partition("=")
                macros[_no_space(name)] = _no_space(strip_comment(value))
                out.append("")
                continue
            if keep_quotes:
                cut = line.find("//")
                out.append(
                    (
                        "" if line.strip().startswith("//") else line[:cut] if cut >= 0 else line
                    ).strip()
                )
            else:
                out.append(strip_comment(line))
        return out

    @staticmethod
    def _block_mask(lines: list[str]) -> list[bool]:
        mask = []
        inside = False
        for line in lines:
            if _no_space(line).upper().startswith("PROCESSCONFIG="):
                inside = True
            mask.append(inside)
            if inside and line.strip().startswith("}"):
                inside = False
        return mask

    # -- globals -----------------------------------------------------------------------------------

    def get_value(self, name: str, outside_blocks: bool = False) -> str | None:
        """The value of the first `name = value` line anywhere in the file (case-insensitive
        name), with all white space removed, as MOOS's GetValue does. With `outside_blocks`,
        lines inside ProcessConfig blocks are skipped, so a block's line never passes for a global
        (QUIRKS.md Q-APPS-3)."""
        wanted = name.lower()
        for line, in_block in zip(self.lines, self._in_block, strict=True):
            if outside_blocks and in_block:
                continue
            key, sep, value = _no_space(line).partition("=")
            if sep and key.lower() == wanted:
                return value
        return None

    def global_line(self, name: str, outside_blocks: bool = True) -> int | None:
        """The file line (1-based) of the `name = value` line that get_value reads."""
        wanted = name.lower()
        for number, (line, in_block) in enumerate(zip(self.lines, self._in_block, strict=True)):
            if outside_blocks and in_block:
                continue
            key, sep, _ = _no_space(line).partition("=")
            if sep and key.lower() == wanted:
                return number + 1
        return None

    def get_port(self, name: str = "ServerPort") -> int | None:
        """A port number global (None if absent); anything but 0-65535 is a ConfigError."""
        value = self.get_value(name)
        if value is None:
            return None
        if not value.isdigit() or int(value) > 65535:
            raise ConfigError(
                f"{name} = {value} is not a port number (0-65535)",
                file=self.path if self.path else "mission file",
                line=self.global_line(name, outside_blocks=False),
                field=name,
            )
        return int(value)

    def get_float(self, name: str, outside_blocks: bool = False) -> float | None:
        value = self.get_value(name, outside_blocks)
        return None if value is None else parse_number(value)

    def get_int(self, name: str) -> int | None:
        number = self.get_float(name)
        return None if number is None else int(number)

    def get_bool(self, name: str) -> bool | None:
        value = self.get_value(name)
        if value is None:
            return None
        if value.upper() == "TRUE":
            return True
        number = self.get_float(name)
        return number is not None and number > 0

    # -- ProcessConfig blocks ----------------------------------------------------------------------

    def _block_lines(self, app: str, keep_quotes: bool = False) -> list[tuple[int, str]] | None:
        """The block's lines as (file line, text)."""
        header = f"PROCESSCONFIG={app}".upper()
        lines = self.quoted_lines if keep_quotes else self.lines
        for i, line in enumerate(lines):
            if _no_space(line).upper() != header:
                continue
            j = i + 1
            while j < len(lines) and not lines[j].strip():
                j += 1
            if j >= len(lines) or not lines[j].strip().startswith("{"):
                return None
            body = []
            first = lines[j].strip()[1:].strip()
            if first:
                body.append((j + 1, first))
            for number, line in enumerate(lines[j + 1 :], start=j + 2):
                if line.strip().startswith("}"):
                    break
                body.append((number, line))
            return body
        return None

    def process_config(self, app: str, keep_quotes: bool = False) -> list[Setting] | None:
        """The block's `name = value` settings in file order, names and values trimmed
        (GetConfigurationAndPreserveSpace), each with its file line; None if there is no such
        block. MOOS's reader removes the first pair of double quotes of a line ("verbatim
        quoting"); apps that disable it (uTimerScript) pass `keep_quotes=True`."""
        body = self._block_lines(app, keep_quotes)
        if body is None:
            return None
        out = []
        for number, line in body:
            name, sep, value = line.strip().partition("=")
            if not sep:
                continue
            value = value.strip()
            if not value and "[" not in line and "]" not in line:
                continue
            out.append(Setting(name.strip(), value, number))
        return out

    def block_value(self, app: str, name: str) -> str | None:
        for key, value, _ in self.process_config(app) or []:
            if key.lower() == name.lower():
                return value
        return None

    # -- Goby TextFormat blocks --------------------------------------------------------------------

    def goby_block(self, app: str) -> GobyBlock | None:
        """The text between the first `{` and the last `}` of the app's block, with `//`
        comments turned into `#` outside quoted strings (Goby's reader: header matched with
        spaces removed, no trailing comment allowed; the block ends at the next line containing
        PROCESSCONFIG)."""
        header = f"processconfig={app}".lower()
        raw = self.raw_lines
        start = next((i for i, ln in enumerate(raw) if ln.replace(" ", "").lower() == header), None)
        if start is None:
            return None
        end = next(
            (i for i in range(start + 1, len(raw)) if "PROCESSCONFIG" in raw[i].upper()), len(raw)
        )
        text = "\n".join(raw[start:end])
        open_at, close_at = text.find("{"), text.rfind("}")
        if open_at < 0 or close_at < open_at:
            return GobyBlock("", start + 1)
        first_line = start + 1 + text.count("\n", 0, open_at)
        body = text[open_at + 1 : close_at]
        return GobyBlock("\n".join(map(_strip_textformat_comments, body.split("\n"))), first_line)

    # -- pAntler -----------------------------------------------------------------------------------

    def antler(self) -> AntlerConfig:
        settings = self.process_config("ANTLER")
        if settings is None:
            raise MissionFileError(
                "no ProcessConfig = ANTLER block in the mission file", file=self.path
            )
        compact = [(_no_space(k), _no_space(v)) for k, v, _ in settings]
        lookup = {k.lower(): v for k, v in reversed(compact)}  # first occurrence wins
        runs = []
        for key, value in compact:
            if key.lower() != "run":
                continue
            spec, _, alias = value.partition("~")
            program, _, opts = spec.partition("@")
            options = {}
            for item in filter(None, opts.split(",")):
                k, _, v = item.partition("=")
                options[k] = v
            extra_key = next(
                (v for k, v in options.items() if k.lower() == "extraprocessparams"), None
            )
            extra = (
                [a for a in lookup.get(extra_key.lower(), "").split(",") if a] if extra_key else []
            )
            runs.append(AntlerRun(program, alias or Path(program).name, options, extra))
        pause = lookup.get("msbetweenlaunches")
        return AntlerConfig(
            runs,
            float(pause) if pause and _NUMERIC.fullmatch(pause) else 1000.0,
            lookup.get("executablepath"),
        )
