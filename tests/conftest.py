"""Test-wide fixtures."""

import pytest


@pytest.fixture(scope="session")
def _session_cache_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("skydome-cache")


@pytest.fixture(autouse=True)
def _private_cache_dir(_session_cache_dir, tmp_path_factory, request, monkeypatch):
    """Point the precomputed model's table cache at a temporary folder, so that tests never
    write into the user's cache folder. The folder is shared by the session (tables at the
    default settings are built once), except for the tests of the cache itself, which get
    one folder each (no such test sees another's tables)."""
    if request.module.__name__.endswith("test_precomputed_cache"):
        folder = tmp_path_factory.mktemp("skydome-cache-own")
    else:
        folder = _session_cache_dir
    monkeypatch.setenv("SKYDOME_CACHE_DIR", str(folder))
    monkeypatch.delenv("SKYDOME_CACHE_LIMIT_BYTES", raising=False)
