"""Session fixtures: rigs of the shared heads, made once and shared by the test modules."""
import pytest

from shared_data import data


@pytest.fixture(scope="session")
def lps_path():
    return data("misc/LeePerrySmith.obj")


@pytest.fixture(scope="session")
def ict_path():
    return data("ict/generic_neutral_mesh.obj")
