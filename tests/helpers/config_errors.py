"""The one check of a bad model config: :func:`fivid.fe.load_model` raises a ConfigError naming ``key`` and saying
each of ``words`` (the value given, what is allowed)."""

import pytest

from fivid.errors import ConfigError
from fivid.fe import load_model


def assert_config_error(cfg, key: str, words) -> None:
    """``load_model(cfg)`` raises a ConfigError whose key path is ``key`` and whose message holds every word."""
    with pytest.raises(ConfigError) as exc:
        load_model(cfg)
    assert exc.value.key == key, str(exc.value)
    for w in words:
        assert w in str(exc.value), str(exc.value)
