"""The axisymmetric sharp-interface reference for closed vesicles at c0 = 0 (Seifert, Berndl &
Lipowsky 1991), independent of the phase-field engines.

The generating curve (r(s), z(s)) has tangent angle ψ(s) = πt + Σ a_k sin(kπt), t = s/L; the
constrained minimum of the reduced bending energy e = ∮(2H)² dA / (16π) at fixed reduced volume
v is found by Newton on the Lagrangian, and each branch followed by continuation in v.
Shapes are scaled to R0 = √(A/4π) = 1; σ (in κ/R0²) and the pressure P (in κ/R0³) are the
multipliers of the shape equation, P = 6 de/dv and σ = P v / 2.

Branches: "prolate" and "oblate" (up–down symmetric, from the sphere) and "stomatocyte" (an
invaginated cup, ending at a limit point near v ≈ 0.66).
"""

from __future__ import annotations

from typing import Any, Sequence

from ._vesicle import axisym_follow, axisym_solve

BRANCHES = ("prolate", "oblate", "stomatocyte")


def solve(branch: str, v: float, nodes: int = 241) -> dict[str, Any]:
    """The stationary shape of ``branch`` at reduced volume ``v``, followed from the branch's
    start (it does not stop at the oblate's self-contact below v ≈ 0.503: see
    ``self_intersecting``).

    Returns a dict: ``branch``, ``v``, ``e``, ``sigma``, ``pressure``, ``length`` (contour
    length L), ``self_intersecting``, ``residual`` (Newton's final KKT residual), and NumPy
    arrays ``s``, ``r``, ``z``, ``psi`` (the contour at ``nodes`` Chebyshev–Lobatto samples,
    pole to pole), ``modes`` and ``coefficients`` (the a_k).

    Raises InvalidInput (field ``v``) if v is not in (0, 1] or the branch does not reach it,
    (field ``nodes``) for fewer than 9 nodes, (field ``branch``) for an unknown branch.
    """
    return axisym_solve(branch, v, nodes)


def follow(branch: str, vs: Sequence[float], nodes: int = 241) -> dict[str, Any]:
    """``branch`` followed over the reduced volumes ``vs`` (values outside (0, 1] skipped): the
    prolate over the whole grid, the oblate down to its first self-intersecting shape, the
    stomatocyte up to its limit point.

    Returns a dict: NumPy arrays ``v``, ``e``, ``sigma``, ``pressure`` (increasing v, where the
    branch exists), ``end`` (where the branch ended, or None), ``branch`` and ``shapes`` (the
    solve() dict of each shape).
    """
    return axisym_follow(branch, list(vs), nodes)


__all__ = ["BRANCHES", "solve", "follow"]
