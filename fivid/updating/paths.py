"""Dotted key paths into a parsed YAML config, and rewriting values in its text.

A path names one value of a config the way fivid's error messages do: ``materials.steel.E``,
``bodies.upper.thickness``, ``contacts[0].normal_stiffness``, ``bodies.lower.corners[1][0]``. Updated
values are written back into the file's *text* at the exact span of the old value (found with PyYAML's
node marks), so comments, key order and flow style (``{E: 210 GPa, nu: 0.3}``) are kept.
"""

from __future__ import annotations

import re

from fivid.errors import ConfigError

__all__ = ["parse_path", "get_path", "set_path", "replace_values"]

_TOKEN = re.compile(r"([^.\[\]]+)|\[(\d+)\]")


def parse_path(path: str) -> list:
    """``"a.b[2].c"`` -> ``["a", "b", 2, "c"]`` (str keys, int list indices).

    Raises
    ------
    ConfigError
        The path is empty or not of the form ``key.key[index]...``.
    """
    parts, pos = [], 0
    text = str(path).strip()
    while pos < len(text):
        if text[pos] == "." and parts and pos + 1 < len(text):
            pos += 1
        m = _TOKEN.match(text, pos)
        if m is None:
            raise ConfigError(f"cannot read the parameter path {path!r} at character {pos + 1}; write keys joined "
                              "by dots and list items as [index], e.g. 'materials.steel.E' or 'contacts[0].mu'")
        parts.append(m.group(1) if m.group(1) is not None else int(m.group(2)))
        pos = m.end()
    if not parts:
        raise ConfigError("empty parameter path; write e.g. 'materials.steel.E'")
    return parts


def _walk(data, parts, path: str):
    node = data
    for k, part in enumerate(parts):
        here = _join(parts[:k])
        if isinstance(part, int):
            if not isinstance(node, list):
                raise KeyError(f"{here or 'the config'} is not a list, so [{part}] does not exist")
            if not 0 <= part < len(node):
                raise KeyError(f"{here} has {len(node)} items; [{part}] does not exist")
        else:
            if not isinstance(node, dict):
                raise KeyError(f"{here or 'the config'} is not a mapping, so it has no key {part!r}")
            if part not in node:
                keys = ", ".join(map(str, node)) or "(none)"
                raise KeyError(f"{_join(parts[:k + 1])!r} does not exist; keys at {here or 'the top'}: {keys}")
        node = node[part]
    return node


def _join(parts) -> str:
    out = ""
    for p in parts:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out


def get_path(data, path: str):
    """The value at ``path`` in nested dicts/lists ``data``; a ``KeyError`` (with a message) when absent."""
    return _walk(data, parse_path(path), path)


def set_path(data, path: str, value) -> None:
    """Set the value at an existing ``path`` of nested dicts/lists ``data`` (in place)."""
    parts = parse_path(path)
    parent = _walk(data, parts[:-1], path)
    _walk(data, parts, path)  # the key must exist: updating adds nothing to a config
    parent[parts[-1]] = value


def replace_values(text: str, values: dict) -> str:
    """``text`` (a YAML document) with the scalar at each path replaced by the given text.

    Parameters
    ----------
    text : str
        The YAML document.
    values : dict
        Path -> new scalar text (written plain: a number with a unit such as ``205.3 GPa``).

    Returns
    -------
    str
    """
    import yaml

    root = yaml.compose(text, Loader=yaml.SafeLoader)
    spans = []
    for path, new in values.items():
        node = root
        for part in parse_path(path):
            if isinstance(part, int):
                node = node.value[part]
            else:
                node = next(v for k, v in node.value if k.value == part)
        if not isinstance(node, yaml.ScalarNode):
            raise ConfigError(f"{path!r} is not a single value (a {node.id}); a parameter must be a number or "
                              "a quantity", key=path)
        spans.append((node.start_mark.index, node.end_mark.index, str(new)))
    for start, end, new in sorted(spans, reverse=True):
        text = text[:start] + new + text[end:]
    return text
