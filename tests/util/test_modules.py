"""import_module_or_file: modules by importable name or by .py path, each loaded once."""

from __future__ import annotations

import pytest

from pygoby.util.modules import import_module_or_file

DATACLASS_MODULE = """\
from __future__ import annotations
from dataclasses import dataclass, field

LOADS = []
LOADS.append(1)

@dataclass
class Point:
    x: float
    tags: list[str] = field(default_factory=list)
"""


def test_a_file_with_dataclasses_loads_once(tmp_path):
    path = tmp_path / "plugin.py"
    path.write_text(DATACLASS_MODULE)
    module = import_module_or_file(str(path))
    assert module.Point(1.5).x == 1.5
    assert import_module_or_file(str(path)) is module and module.LOADS == [1]


def test_a_broken_file_is_not_left_half_loaded(tmp_path):
    path = tmp_path / "broken.py"
    path.write_text("VALUE = 1\nraise RuntimeError('broken plugin')\n")
    for _ in range(2):  # the second attempt runs the file again instead of returning a stub
        with pytest.raises(RuntimeError, match="broken plugin"):
            import_module_or_file(str(path))


def test_an_importable_name():
    assert (
        import_module_or_file("pygoby.util.modules").import_module_or_file is import_module_or_file
    )
