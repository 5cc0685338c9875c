"""Test-wide fixtures."""

import pytest


@pytest.fixture(autouse=True)
def _private_cache_dir(tmp_path_factory, monkeypatch):
    """Point the precomputed model's table cache at a temporary folder, so that tests never
    write into the user's cache folder (one folder per test: no test sees another's tables)."""
    monkeypatch.setenv("SKYDOME_CACHE_DIR", str(tmp_path_factory.mktemp("skydome-cache")))
    monkeypatch.delenv("SKYDOME_CACHE_LIMIT_BYTES", raising=False)
