"""Linear algebra that both adapters' engine steps share."""

import numpy as np
from scipy.linalg import lapack


def linear_solution(matrix, rhs):
    """x of matrix x = rhs, one system (n, n) or many stacked (..., n, n): one by LAPACK's dgesv itself, the
    routine np.linalg.solve calls, without numpy's checks around it, which cost more than the solve of a few
    dofs (the same numbers)."""
    if matrix.ndim > 2:
        return np.linalg.solve(matrix, rhs[..., None])[..., 0]
    _, _, x, info = lapack.dgesv(matrix, rhs)
    if info > 0:
        raise np.linalg.LinAlgError("Singular matrix")
    return x
