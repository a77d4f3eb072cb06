"""The axisymmetric sharp-interface reference for closed vesicles in the spontaneous-curvature
model (Seifert, Berndl & Lipowsky 1991), independent of the phase-field engines.

The generating curve (r(s), z(s)) has tangent angle ψ(s) = πt + Σ a_k sin(kπt), t = s/L; the
constrained minimum of the reduced bending energy e = ∮(2H − c̄0)² dA / (16π) at fixed reduced
volume v (c̄0 = c0 R0, the reduced spontaneous curvature; a sphere has e = (1 − c̄0/2)²) is found
by Newton on the Lagrangian, and each branch followed by continuation in v. Shapes are scaled to
R0 = √(A/4π) = 1; σ (in κ/R0²) and the pressure P (in κ/R0³) are the multipliers of the shape
equation, P = 6 de/dv and σ = P v / 2 + c̄0 J − c̄0²/2 (J the reduced integrated mean
curvature, ``mean_curvature``; at c̄0 = 0, σ = P v / 2).

Branches: "prolate" and "oblate" (up–down symmetric, from the sphere) and "stomatocyte" (an
invaginated cup, ending at a limit point near v ≈ 0.66 at c̄0 = 0); with ``ade`` or ``bc``
also "pear".
"""

from __future__ import annotations

from typing import Any, Sequence

from ._vesicle import axisym_follow, axisym_solve, axisym_updown

BRANCHES = ("prolate", "oblate", "stomatocyte")


def solve(
    branch: str,
    v: float,
    nodes: int = 241,
    c0: float = 0.0,
    ade: tuple[float, float] | dict[str, float] | None = None,
    bc: float | None = None,
) -> dict[str, Any]:
    """The stationary shape of ``branch`` at reduced volume ``v`` and reduced spontaneous
    curvature ``c0`` (c̄0 = c0 R0; 0 by default), followed from the branch's start (it does not
    stop at the oblate's self-contact below v ≈ 0.503 at c̄0 = 0: see ``self_intersecting``).

    ``ade=(alpha, da0)`` (or ``{"alpha": α, "da0": Δa0}``) solves the area-difference-elasticity
    model, w = e + πα(Δa − Δa0)², instead: the lowest stable ADE shape of the branch at this v
    (Newton on the ADE functional, started from the branch's bilayer-couple path; branches
    "prolate", "oblate", "stomatocyte", "pear"). ``bc=da`` solves the bilayer couple, Δa held
    at ``da`` (c0 must be 0). Such a shape is a stationary SC shape at ``c0_eff``.

    Returns a dict: ``branch``, ``v``, ``c0``, ``e``, ``mean_curvature`` (J = ∮2H dA / (8π R0)),
    ``da`` (the reduced area difference, = J), ``model`` ("sc", "ade" or "bc"), ``w`` (the
    model's energy: e, or w for ADE), ``c0_eff``, ``sigma``, ``pressure``, ``length`` (contour
    length L), ``self_intersecting``, ``residual`` (Newton's final KKT residual), and NumPy
    arrays ``s``, ``r``, ``z``, ``psi`` (the contour at ``nodes`` Chebyshev–Lobatto samples,
    pole to pole), ``modes`` and ``coefficients`` (the a_k of ψ = πτ + Σ a_k sin kπτ), and
    ``neck_map``: None where τ = s/L, else the stretching of τ that clusters the modes at a
    narrow neck (below 0.1 R0), a dict ``centre`` (the neck's arclength fraction t_n),
    ``half_width`` (of the node-density kernel, in s/L), ``background`` (the uniform share of
    the node density) and ``mirrored`` (True on the up–down symmetric branches: the same kernel
    at 1 − t_n).

    Raises InvalidInput (field ``v``) if v is not in (0, 1] or the branch does not reach it,
    (field ``nodes``) for fewer than 9 nodes, (field ``c0``) for a c0 that is not finite,
    (field ``branch``) for an unknown branch, (``alpha``, ``da0``, ``da``) for an ADE or BC
    shape that does not exist or an α that is not positive.
    """
    if isinstance(ade, dict):
        ade = (float(ade["alpha"]), float(ade["da0"]))
    return axisym_solve(branch, v, nodes, c0, ade, bc)


def follow(branch: str, vs: Sequence[float], nodes: int = 241, c0: float = 0.0) -> dict[str, Any]:
    """``branch`` followed over the reduced volumes ``vs`` (values outside (0, 1] skipped) at
    reduced spontaneous curvature ``c0``: the prolate over the whole grid, the oblate down to
    its first self-intersecting shape, the stomatocyte up to its limit point.

    Returns a dict: NumPy arrays ``v``, ``e``, ``sigma``, ``pressure`` (increasing v, where the
    branch exists), ``end`` (where the branch ended, or None), ``branch``, ``c0`` and
    ``shapes`` (the solve() dict of each shape).
    """
    return axisym_follow(branch, list(vs), nodes, c0)


def updown(v: float, nodes: int = 241) -> list[dict[str, Any]]:
    """Where the bilayer-couple prolate at reduced volume ``v`` (c0 = 0) loses or regains
    up–down stability: the zeros of its up–down test function μ (the lowest eigenvalue of the
    second variation on up–down odd perturbations) along its path in Δa from 0 to 2.5, walked
    from small Δa while its neck is wider than 0.015 R0, each refined by the secant method in
    Δa. The first loss is where the pear leaves the prolate; at v ≥ 0.86 the prolate budding at
    both poles regains its stability before its necks close. By the same argument the ADE
    prolate of the same shape changes its stability there (an odd perturbation moves neither Δa
    nor v at first order); its Δa0 is ``da + c0_eff / (2π α)``.

    Returns a list, in path order, of dicts: ``da``, ``loses`` (True where μ falls through 0,
    False where it rises), ``c0_eff``, ``neck`` (the narrowest waist, in R0, or None) and
    ``shape`` (the solve() dict of the prolate at the zero).

    Raises InvalidInput (field ``v``) if v is not in (0, 1), (field ``nodes``) for fewer than 9
    nodes.
    """
    return axisym_updown(v, nodes)


__all__ = ["BRANCHES", "solve", "follow", "updown"]
