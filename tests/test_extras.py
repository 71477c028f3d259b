"""The core (DCCL, goby-acomms, MOOS) loads none of the packages of pyproject's extras, and a
feature whose extra is missing says which `pip install 'pygoby[...]'` brings it."""

from __future__ import annotations

import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from pygoby.util.errors import MissingExtraError
from pygoby.util.extras import needs_extra

REPO = Path(__file__).resolve().parents[1]


def extras_packages() -> set[str]:
    """The import names of the packages only the extras install (their distribution names)."""
    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    names = set()
    for extra, requirements in project["optional-dependencies"].items():
        if extra in ("dev", "all"):
            continue
        for requirement in requirements:
            names.add(re.match(r"[A-Za-z0-9_.-]+", requirement).group().replace("-", "_"))
    return names


def test_the_extras_are_the_feature_packages():
    assert {"matplotlib", "gsw", "pyarrow", "rich", "textual", "starlette", "uvicorn", "lupa"} <= (
        extras_packages()
    )


def test_importing_the_core_loads_no_extra_package():
    check = (
        "import sys\n"
        "import pygoby.dccl, pygoby.acomms, pygoby.moos\n"
        # and the acomms-on-MOOS layer with the apps over it that need no extra
        "import pygoby.frontseat, pygoby.moosacomms.acomms_config, pygoby.moosacomms.goby11\n"
        "import pygoby.apps.pacommshandler, pygoby.apps.ptranslator, pygoby.apps.ifrontseat\n"
        "print(' '.join(sorted({name.split('.')[0] for name in sys.modules})))\n"
    )
    loaded = subprocess.run(
        [sys.executable, "-c", check], capture_output=True, text=True, check=True
    ).stdout.split()
    assert "pygoby" in loaded  # the check ran
    assert not extras_packages() & set(loaded)


def test_a_missing_package_names_its_extra():
    with (
        pytest.raises(
            MissingExtraError, match=r"netsim reports needs .*pip install 'pygoby\[sim\]'"
        ),
        needs_extra("sim", "netsim reports"),
    ):
        import pygoby_no_such_package  # noqa: F401


BLOCK = """
import importlib.abc, sys
class Block(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.split('.')[0] == {package!r}:
            raise ModuleNotFoundError(f"No module named {{name!r}}", name=name)
sys.meta_path.insert(0, Block())
"""


def run_without(package: str, code: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", BLOCK.format(package=package) + code],
        capture_output=True,
        text=True,
    )


def test_netsim_report_without_matplotlib_names_the_sim_extra(tmp_path):
    log = tmp_path / "events.jsonl"
    log.write_text("")
    done = run_without(
        "matplotlib",
        "from pygoby.cli import main\n"
        f"raise SystemExit(main(['netsim', 'report', {str(log)!r}, '-o', {str(tmp_path)!r}]))\n",
    )
    assert done.returncode == 1
    assert "pip install 'pygoby[sim]'" in done.stderr and "Traceback" not in done.stderr


def test_log_plot_without_matplotlib_names_the_sim_extra(tmp_path):
    log = REPO / "tests" / "data" / "alog" / "acomms.alog"
    done = run_without(
        "matplotlib",
        "from pygoby.cli import main\n"
        f"raise SystemExit(main(['log', 'plot', {str(log)!r}, '-o', {str(tmp_path)!r}]))\n",
    )
    assert done.returncode == 1
    assert "log plots needs" in done.stderr and "pip install 'pygoby[sim]'" in done.stderr
    assert "Traceback" not in done.stderr and not list(tmp_path.iterdir())


def test_liaison_without_starlette_names_the_topside_extra():
    done = run_without(
        "starlette",
        "from pygoby.cli import main\nraise SystemExit(main(['liaison', '--example_config']))\n",
    )
    assert done.returncode == 1
    assert "pip install 'pygoby[topside]'" in done.stderr and "Traceback" not in done.stderr
