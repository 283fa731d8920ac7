import pytest

from quickrelease import preset


@pytest.fixture(scope="session")
def paper_device():
    return preset("paper")


#: The release identified from Table 7's printed inputs (E_S = 2900 J, t_F = 1.05 s), rounded to 0.01 N:
#: a realistic friction pair for solver tests (the solvers do not depend on how it was found).
PAPER_CASE = dict(E_S=2900.0, alpha0=0.2, F1=419.85, F2=804.57)
