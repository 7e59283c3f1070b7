"""Built-in configs looked up by name: rig profiles (``--rig labdaq``), example models (``triboair_coarse``) and
friction-damper models (``fivid damper frf seed004_model1``).

The files live once, in the repository's ``configs/rigs/``, ``configs/models/`` and ``configs/dampers/`` (with the models'
profile data in ``configs/models/profiles/``). A wheel ships a copy of them as package data in
``fivid/data/configs/`` (copied at build time by ``setup.py``), so a name works outside a checkout too.
A name is looked up in the checkout first (the files a developer edits), then in the installed copy.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["KINDS", "builtin_folders", "find_builtin", "builtin_names"]

#: kinds of built-in config: folder name under ``configs/`` -> what one file is
KINDS = {"rigs": "rig profile", "models": "model config", "dampers": "damper model"}

_PACKAGE = Path(__file__).resolve().parent


def builtin_folders(kind: str) -> list[Path]:
    """Existing folders holding built-in configs of ``kind`` (a key of :data:`KINDS`), searched in order:
    the checkout's ``configs/<kind>`` then the installed ``fivid/data/configs/<kind>``."""
    if kind not in KINDS:
        raise ValueError(f"unknown kind of built-in config {kind!r}; known: {', '.join(KINDS)}")
    candidates = [_PACKAGE.parent / "configs" / kind, _PACKAGE / "data" / "configs" / kind]
    return [folder for folder in candidates if folder.is_dir()]


def find_builtin(kind: str, name: str) -> Path | None:
    """The file of the built-in config ``name`` (``"labdaq"``, ``"triboair_coarse"``; ``.yaml`` optional), or None."""
    stem = name[:-5] if name.endswith(".yaml") else name
    if not stem or any(c in stem for c in "/\\"):
        return None
    return next((f / f"{stem}.yaml" for f in builtin_folders(kind) if (f / f"{stem}.yaml").is_file()), None)


def builtin_names(kind: str) -> list[str]:
    """Names of the built-in configs of ``kind``, sorted."""
    return sorted({p.stem for folder in builtin_folders(kind) for p in folder.glob("*.yaml")})
