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
