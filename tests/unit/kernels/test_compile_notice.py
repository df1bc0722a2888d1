"""The first Numba run after install announces its compilation: a cache
without the kernels' indexes is cold, one with all of them is not."""

from __future__ import annotations

import logging
import sys

import pytest

from xfemslip import kernels


@pytest.fixture
def empty_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(kernels, "NUMBA_CACHE", True)
    return tmp_path


def test_empty_cache_is_cold(empty_cache):
    assert kernels.cache_is_cold()


def test_cache_with_every_module_is_warm(empty_cache):
    folder = empty_cache / "kernels_0123"
    folder.mkdir()
    for stem in kernels.JIT_MODULES[:-1]:
        (folder / f"{stem}.f-10.py311.nbi").write_bytes(b"")
    assert kernels.cache_is_cold()  # one module still missing
    (folder / f"{kernels.JIT_MODULES[-1]}.g-20.py311.nbi").write_bytes(b"")
    assert not kernels.cache_is_cold()


def test_cache_switched_off_always_compiles(empty_cache, monkeypatch):
    for stem in kernels.JIT_MODULES:
        (empty_cache / f"{stem}.f-1.py311.nbi").write_bytes(b"")
    assert not kernels.cache_is_cold()
    monkeypatch.setattr(kernels, "NUMBA_CACHE", False)
    assert kernels.cache_is_cold()


def test_backend_announces_a_cold_compilation(empty_cache, monkeypatch, caplog):
    """backend("numba") with a cold cache, before the JIT module is imported:
    one INFO line with the expected time; not for NumPy."""
    imported = []
    monkeypatch.delitem(sys.modules, "xfemslip.kernels.jit", raising=False)
    monkeypatch.setattr(
        kernels.importlib, "import_module", lambda name: imported.append(name)
    )
    with caplog.at_level(logging.INFO, logger="xfemslip.kernels"):
        kernels.backend("numpy")
        assert caplog.records == []
        kernels.backend("numba")
    (record,) = caplog.records
    assert record.getMessage().startswith("compiling kernels (first run, about 15 s")
    assert imported == ["xfemslip.kernels.vectorized", "xfemslip.kernels.jit"]
