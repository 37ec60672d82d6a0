"""Verification of dual (Farkas) certificates of infeasibility, from the IR alone.

The problem is: find ``x`` with ``F_i(x) >= 0`` (``> 0`` when strict) for every LMI, and
linear rows ``l_r(x) = a_r0 + a_r . x`` that are ``== 0`` (``eq``) or ``>= 0`` / ``> 0``
(``ge``). A certificate is ``{"lmis": [Z_i], "linear": y}`` (the layout of
:attr:`lmic.solution.Solution.farkas`; ``Z_i`` dense symmetric, paired with the normalised
``F_i``, i.e. the conic-dual convention ``z in K*``). Write

    ``g_k = sum_i <F_i^(k), Z_i> + sum_r a_rk y_r``   for ``k = 0 .. n``

(``<A, B> = trace(A B)``; ``F_i^(0)`` and ``a_r0`` are the constant terms). For every ``x``

    ``sum_i <F_i(x), Z_i> + sum_r y_r l_r(x) = g_0 + sum_{k >= 1} x_k g_k``.        (*)

Conditions
----------
Signs: ``Z_i >= 0`` and ``y_r >= 0`` on ``ge`` rows (``y_r`` is free on ``eq`` rows). Then at a
feasible ``x`` the left side of (*) is ``>= 0``.

* **Closed infeasibility** (proves the non-strict problem, hence also the strict one,
  infeasible): ``g_k = 0`` for ``k >= 1`` and ``g_0 < 0``: (*) would give ``0 <= g_0 < 0``.
* **Strict infeasibility** (proves only the strict problem infeasible): ``g_k = 0`` for
  ``k >= 1``, ``g_0 <= 0`` and ``tau > 0``, where ``tau = sum_{i strict} tr Z_i +
  sum_{r strict} y_r``. If ``F_i(x) >= mu I`` on the strict LMIs and ``l_r(x) >= mu`` on the
  strict rows, the left side of (*) is ``>= mu tau``, so ``mu <= g_0 / tau <= 0``. This is the
  certificate of a homogeneous strict LMI (``F0 = 0``, ``g_0 = 0``, e.g. ``A^T P + P A < 0,
  P > 0`` for an unstable ``A``) and of the max-margin reduction of :mod:`lmic.reductions.strict`.

With floating-point certificates the equalities hold only approximately. The verifier first
projects each ``Z_i`` onto the PSD cone and clips ``y`` on ``ge`` rows to ``>= 0`` (the part
removed must be below ``tol`` relative to ``eta = sum tr Z_i + sum |y_r|``; the certificate is
rescaled to ``eta = 1``), then recomputes ``g`` from the repaired certificate, so the sign
conditions hold by construction and only these tolerances remain, each relative:

``rel_residual = max_k |g_k| / c_k <= tol`` with ``c_k = sum_i ||F_i^(k)||_F + sum_r |a_rk|``
(how much ``x_k`` can move the constraints; with ``eta = 1`` this bounds the relative margin a
point could still have, since ``|<F_i^(k), Z_i>| <= ||F_i^(k)||_F``), and ``g_0 < -tol c_0``
(closed), or ``g_0 <= tol c_0`` and ``tau >= tol`` (strict).

What a verified float certificate proves, quantitatively, is reported: for the closed case
no feasible ``x`` with ``||x||_inf < radius = -g_0 / ||g_{1:}||_1``; for the strict case no
``x`` with margin ``mu > margin_bound = (g_0 + ||g_{1:}||_1 ||x||_inf) / tau`` (reported for
``||x||_inf = 1``; the margin bound scales with ``||x||`` for homogeneous problems, so it is a
bound on the *relative* margin).

Global or bounded: what a certificate proves about the ORIGINAL problem
-----------------------------------------------------------------------
Backends reduce strict constraints before solving (:mod:`lmic.reductions.strict`): the
``max-margin`` problem adds a margin ``t``, a cap ``t <= 1`` and, for scale-free problems, a
trace normalisation ``tr F_i(x) <= d_i``. The dual of such a problem carries multipliers of those
extra rows (the "box term"); :func:`verify_farkas` is always run on the ORIGINAL problem with
the multipliers of the original constraints only, so no box multiplier can enter ``g``. What
remains is the float residual ``g_k != 0`` (``k >= 1``), and that is what decides the scope
(:func:`scope`):

* **exact proof** (:func:`prove_farkas`): ``g_k = 0`` for ``k >= 1`` in rational arithmetic,
  ``Z_i >= 0`` and the separation exactly. Then (*) holds for every ``x`` with no ``x`` term,
  so no ``x`` at all is feasible: a **global** proof.
* **homogeneous problems** (every ``F_i^(0) = 0`` and ``a_r0 = 0``: the strict feasible set is
  an open cone, e.g. Lyapunov LMIs) with a verified *strict* certificate: ``g_0 = 0`` exactly
  (a sum of exact zeros), and (*) gives ``mu tau <= ||x||_inf ||g_{1:}||_1`` for every ``x``
  with margin ``mu``. Since ``x -> s x`` (``s > 0``) maps the feasible cone onto itself, the
  trace normalisation of the reduction loses nothing, and the bound is scale-free: no point
  *at any scale* has relative margin ``mu / ||x||_inf`` above ``rho = ||g_{1:}||_1 / tau``
  (recorded). That bounds the relative margin and does not exclude a point with a smaller one,
  so it is **bounded**: in the normalisation ``margin >= 1`` no solution with ``||x||_inf <
  1 / rho`` (the radius recorded). It was once called global; a Hurwitz ``A`` (an eigenvalue at
  ``-3e-8``, ill-conditioned eigenvectors) has Lyapunov solutions of relative margin ``1e-10``,
  proved in rational arithmetic, where a float certificate with ``rho = 4.5e-8`` verified.
* **everything else** (an inhomogeneous problem with a float certificate): (*) gives
  ``0 <= g_0 + ||x||_inf ||g_{1:}||_1`` at any feasible ``x``, so only points with
  ``||x||_inf < R = -g_0 / ||g_{1:}||_1`` are excluded: a **bounded** proof, "no solution with
  ``||x||_inf <= R``", never called infeasible. This is not a formality: the problem
  ``[[x, 1], [1, 1e-5]] > 0`` is feasible exactly for ``x > 1e5``, and SDPA and SCS return
  certificates that verify to ``1e-6`` with ``R ~ 4e4`` (``tests/engine/test_engine.py``). To go
  further: an exact proof (``--exact``), another backend (another ray), or a larger ``R``
  (a more accurate ray). A float ``g_k`` is known only up to the rounding of its own
  evaluation (``residual_floor``: a few ``eps`` per term, each term bounded by ``c_k``), so
  ``R`` uses ``||g_{1:}||_1`` plus that bound: a float residual of exactly ``0.0`` (an exact
  certificate checked in float) gives a large but finite ``R``, never "no solution with
  ``||x||_inf <= inf``"; only the exact proof makes it global.

Repair of inaccurate certificates
---------------------------------
Interior-point solvers return the Farkas ray only to their own accuracy (SDPA on
``uir.thm5_1``: relative residual 2.8e-5, all of it in one variable whose every term has the
same sign, i.e. a genuine leak of the multiplier into directions that must carry no weight,
not a cancellation the measure misjudges). When the solver's certificate fails *only* the
tolerances and is within :data:`REPAIR_MAX` of one (relative residual, PSD and sign
violations), :func:`repair_farkas` looks for an exact-enough certificate next to it, on its
support: writing ``Z_i = U_i U_i^T`` (the eigenvectors of ``Z_i`` above ``1e-12`` of the
largest multiplier, scaled by the square roots of the eigenvalues) and ``y_r`` on the rows it
uses, it solves the least-norm correction ``Z_i -> U_i (I + E_i) U_i^T``, ``y_r -> y_r (1 +
e_r)`` of the linear conditions ``g_k = 0`` (``k >= 1``), and takes the step damped so that
``||E_i||_2, |e_r| <= 1/2``: the multipliers stay in the cone (this is the Dikin ellipsoid of
the certificate's face), the residual shrinks by the step each iteration, and a full step
ends the repair with the residual at round-off. The repaired certificate is then verified by
exactly the same conditions as any other certificate and recorded (``certificate``), next to
the solver's original numbers (``original``). A repair is a search for a certificate, and
its result is checked, not trusted: on a feasible problem nothing can pass (``tests``: a
perturbed certificate of a nearby unstable system stays unverified).

Exact certificates (:func:`prove_farkas`)
-----------------------------------------
A verified float certificate still has ``g_k ~ 1e-14`` instead of ``0``. :func:`prove_farkas`
turns it into an exact one: on the certificate's face (``Z_i = V_i S_i V_i^T``, ``V_i`` the
eigenvectors above ``1e-9`` of the largest multiplier, rounded to rationals ``2^-50``; ``y_r``
on the rows it uses) the conditions ``g_k = 0`` are linear in ``(S_i, y)`` with exact rational
coefficients. Entries of ``V_i`` below ``2^-40`` are LAPACK's round-off on coordinates the face
does not touch (a zero row of ``Z_i``) and are set to exact zeros before the rounding: kept,
they tilt the face out of its coordinate subspace, an equation that vanishes identically on the
true face binds in exact arithmetic, and the projection below has to cancel an O(1) part of the
multiplier (how much noise LAPACK leaves depends on its build: this decided the SDPA test case
on one machine and not on another). The rounded ``(S_i, y)`` is projected exactly onto their
solution space (over an independent subset of the equations, python-flint). When that leaves
the cone (an eigenvalue of ``S_i`` smaller than the projection's correction), a second attempt
first moves the float point towards the analytic centre of the face's certificates (log-det
barrier, Newton steps in the null space of the float equations): by the smallest step of a
grid that leaves every eigenvalue a float margin, so the certificate stays close to the
solver's. Two more failures are searched around (:mod:`lmic.certify.farkas_face`). A solver's ray is
accurate only to its tolerance: the span of its top eigenvectors is tilted by ``1e-6`` or so
off the true face, and when the certificates' face is spanned by rational vectors (structured
data: ``z = e_4 - e_7``) the exact conditions then bind where they vanish on the true face and
force ``S_i = 0`` ("no exact separation: g_0 = 0"); a third attempt replaces the face basis by
its canonical basis (identity on pivot rows) rounded to fractions with small denominators, when
every entry is within a tolerance of one. And which eigenvalues are the certificate and which
the solver's noise is not a fixed ratio (the same problem scaled by ``1e3`` moves the noise from
``1e-8`` to ``1e-9`` of the largest multiplier): after the given thresholds, the largest
eigenvalue gaps of every block define further faces (scale-free).
Either way the result is only a candidate; then, exactly: every ``S_i`` is
positive semidefinite (so is ``Z_i``), ``y_r >= 0`` on ``ge`` rows, ``g_k = 0`` for
``k >= 1`` by construction, and ``g_0 < 0`` (closed) or ``g_0 <= 0`` with ``tau > 0``
(strict). Nothing is left to tolerance: the problem is infeasible as stated by its IR.

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from lmic.ir.problem import LMI, LinearConstraints, Objective, Problem, Variable
>>> # p >= 0 and -1 - p >= 0 cannot both hold: Z = [[1]], [[1]] gives g0 = -1, g1 = 0
>>> p = Problem([Variable("p", "scalar", (1, 1))],
...             [LMI("p >= 0", 1, sp.csc_matrix([[0., 1.]]), strict=False),
...              LMI("-1 - p >= 0", 1, sp.csc_matrix([[-1., -1.]]), strict=False)],
...             LinearConstraints.empty(1), Objective("feasibility", [0, 0]))
>>> r = verify_farkas(p, {"lmis": [np.eye(1), np.eye(1)], "linear": []})
>>> r["verified"], r["kind"]
(True, 'closed')

The module is split by job and re-exports every public name: ray verification and repair
(:mod:`lmic.certify.farkas_ray`), exact global proofs (:mod:`lmic.certify.farkas_exact`) and
the scope of what a certificate proves (:mod:`lmic.certify.farkas_scope`); the faces the exact
proof tries are found by :mod:`lmic.certify.farkas_face`.
"""

from __future__ import annotations

from lmic.certify.farkas_exact import EXACT_MAX_ENTRIES, prove_farkas, prove_infeasible
from lmic.certify.farkas_ray import REPAIR_MAX, REPAIR_MAX_ENTRIES, ray_report, repair_farkas, verify_farkas
from lmic.certify.farkas_scope import is_homogeneous, scope

__all__ = [
    "verify_farkas",
    "ray_report",
    "scope",
    "is_homogeneous",
    "repair_farkas",
    "prove_farkas",
    "prove_infeasible",
    "REPAIR_MAX",
    "REPAIR_MAX_ENTRIES",
    "EXACT_MAX_ENTRIES",
]
