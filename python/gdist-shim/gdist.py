"""A module named ``gdist`` that is ``bipolar.gdist``: put this folder first on ``PYTHONPATH``
to run code (or tvb-gdist's own test suite) written for tvb-gdist against bipolar. It is not
installed with the package, so an installed tvb-gdist is never shadowed by accident."""

from bipolar.gdist import *  # noqa: F401,F403
from bipolar.gdist import GEODESIC_INF, __all__  # noqa: F401
