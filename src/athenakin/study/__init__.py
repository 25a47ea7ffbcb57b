"""Study parameters and dual quaternions (paper Eq. 1-4 and the joint transforms of Eq. 6).

Quaternions are scalar first, ``(w, x, y, z)``; :func:`quaternion_xyzw_from_wxyz`,
:func:`quaternion_wxyz_from_xyzw` and the ``scipy_rotation`` functions convert to and
from scalar-last libraries (scipy, ROS, Pinocchio).
"""

from ._interop import (
    quaternion_from_scipy_rotation,
    quaternion_wxyz_from_xyzw,
    quaternion_xyzw_from_wxyz,
    scipy_rotation_from_quaternion,
)
from ._joints import (
    study_G,
    study_G_from_half_tangent,
    study_M,
    study_M_from_half_tangent,
)
from ._study import (
    STUDY_QUADRIC_TOL,
    check_study,
    dq_conj_dual,
    dq_conj_full,
    dq_conj_quaternion,
    dq_inverse,
    dq_multiply,
    is_on_study_quadric,
    paper_matrix_from_study,
    quaternion_from_rotation,
    quaternion_multiply,
    rotation_from_quaternion,
    study_equal,
    study_from_transform,
    study_normalize,
    study_quadric_residual,
    transform_from_study,
)

__all__ = [
    "STUDY_QUADRIC_TOL",
    "check_study",
    "dq_conj_dual",
    "dq_conj_full",
    "dq_conj_quaternion",
    "dq_inverse",
    "dq_multiply",
    "is_on_study_quadric",
    "paper_matrix_from_study",
    "quaternion_from_rotation",
    "quaternion_from_scipy_rotation",
    "quaternion_multiply",
    "quaternion_wxyz_from_xyzw",
    "quaternion_xyzw_from_wxyz",
    "rotation_from_quaternion",
    "scipy_rotation_from_quaternion",
    "study_G",
    "study_G_from_half_tangent",
    "study_M",
    "study_M_from_half_tangent",
    "study_equal",
    "study_from_transform",
    "study_normalize",
    "study_quadric_residual",
    "transform_from_study",
]
