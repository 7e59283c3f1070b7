"""Build hook: ship the built-in rig profiles, example models and damper models as package data.

The files live once, in ``configs/rigs/``, ``configs/models/`` and ``configs/dampers/`` (the paths the docs, tests and run
configs use). Building a wheel copies them into ``fivid/data/configs/`` inside the wheel, where
:mod:`fivid.builtin` finds them by name (``fivid ingest --rig labdaq``, ``fivid modes triboair_coarse``)
when fivid runs outside a checkout. All metadata is in pyproject.toml.
"""

from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

ROOT = Path(__file__).resolve().parent
# folder under configs/ -> file patterns shipped (model profile data sits in configs/models/profiles/)
SHIPPED = {"rigs": ("*.yaml",), "models": ("*.yaml", "profiles/*.csv"), "dampers": ("*.yaml",)}


class build_py_with_configs(build_py):
    """``build_py`` that also copies configs/{rigs,models,dampers} into ``<build>/fivid/data/configs/``."""

    def run(self):
        super().run()
        if getattr(self, "editable_mode", False):  # an editable install reads the checkout's configs/
            return
        for kind, patterns in SHIPPED.items():
            for pattern in patterns:
                for src in sorted((ROOT / "configs" / kind).glob(pattern)):
                    rel = src.relative_to(ROOT / "configs")
                    dst = Path(self.build_lib) / "fivid" / "data" / "configs" / rel
                    self.mkpath(str(dst.parent))
                    self.copy_file(str(src), str(dst))


setup(cmdclass={"build_py": build_py_with_configs})
