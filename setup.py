"""Build step: compile pygoby's own .proto files into `_pb2.py` modules and `.pyi` stubs.

Everything else is declared in pyproject.toml. build_py also runs for editable installs
(`pip install -e .`), where the modules are written beside the .proto files in src/.
"""

import importlib.util
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

_GENERATE = Path(__file__).resolve().parent / "src" / "pygoby" / "protobuf" / "generate.py"


class build_py_with_protos(build_py):  # noqa: N801 (setuptools command names are lower case)
    def run(self) -> None:
        # loaded by path: pygoby itself cannot be imported before it is built
        spec = importlib.util.spec_from_file_location("pygoby_generate_protos", _GENERATE)
        assert spec is not None and spec.loader is not None
        generate = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(generate)
        if generate.is_stale():
            generate.generate()
        super().run()


setup(cmdclass={"build_py": build_py_with_protos})
