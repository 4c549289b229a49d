"""Session fixtures: rigs of the shared heads, made once and shared by the test modules."""
import pytest

from shared_data import data


@pytest.fixture(scope="session")
def lps_path():
    return data("misc/LeePerrySmith.obj")


@pytest.fixture(scope="session")
def ict_path():
    return data("ict/generic_neutral_mesh.obj")


class _Rigs:
    """Rigs of shared heads, made on first use and kept for the session."""

    def __init__(self):
        self._cache = {}

    def __call__(self, rel, density="medium", **kwargs):
        import autobones

        key = (rel, density, tuple(sorted(kwargs.items())))
        if key not in self._cache:
            self._cache[key] = autobones.place(None if rel is None else data(rel), density=density, **kwargs)
        return self._cache[key]


@pytest.fixture(scope="session")
def rigs():
    return _Rigs()


def _measured_slow():
    """Node ids listed in tests/slow_tests.txt (measured by tools/slow_tests.py)."""
    from pathlib import Path

    lines = (Path(__file__).parent / "slow_tests.txt").read_text().splitlines()
    return {line.strip() for line in lines if line.strip() and not line.startswith("#")}


def pytest_collection_modifyitems(config, items):
    # the tests a measured full run found slow (>= 2 s) join the ones marked by hand, so that
    # `pytest -m "not slow"` is a few-minute run (README, Tests)
    slow = _measured_slow()
    for item in items:
        if item.nodeid in slow:
            item.add_marker(pytest.mark.slow)
