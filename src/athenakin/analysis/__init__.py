"""Jacobians, singularities and workspace of the ATHENA robot (tentative init)."""
from ._jacobians import *  # noqa
from ._singularities import *  # noqa
from ._workspace import *  # noqa
