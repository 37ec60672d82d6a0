"""Observer models with their own simulation loop: one per observer family of the source papers.

The models of :mod:`lmic.simulate.models` share one plant and one loop; the families here each
need their own (a delay line, an uncertainty realisation, reduced coordinates, a continuous
plant sampled at the period of a discrete observer, a descriptor plant with unknown inputs, a
closed loop). Each model implements :meth:`Custom.custom_run` (the trajectory for a
``simulation:`` section) and, where the theorem certifies a number, :meth:`Custom.checks`
(see :mod:`lmic.simulate.certificate`).

``reduced`` (discrete) — Wang, Song & Zhang (2015) (18), ``qib.thm2`` / ``qib.cor2``
    ``z^+ = A_Z z^ + B_Z y + H f(x^) + K (y(k+1) - C zeta)``,
    ``zeta = A N z^ + A M y + f(x^)``, ``x^ = N z^ + M y`` with ``A_Z = H A N``,
    ``B_Z = H A M``; the plant is ``x+ = A x + f(x, u)`` (a known input enters through f).
    Roles ``A, C, H, N, M, K``.
``robust`` (discrete) — Luenberger observer ``x^+ = A x^ + f(x^) + L (y - C x^)`` against an
    uncertain plant with a time-varying state (and output) delay,
    ``x+ = (A + MA F NF) x + (Ad + MAd F NF) x(k - tau) + f(x) + D1 w``,
    ``y = (C + MC F NF) x + (Cd + MCd F NF) x(k - tau) + D2 w``, performance ``z = Hz e``
    (``delay_a``, ``delay_b``, ``uncertain_dt``). Roles ``A, C, L``; optional ``Ad, Cd, D1,
    D2, MA, MAd, MC, MCd, NF, Hz``, the certified L2 gain ``gamma`` and decay rate ``decay``,
    and the delay bounds ``tau1, tau2``.
``euler`` (discrete) — Abbaszadeh & Marquez (sampled_euler): the observer of the Euler model
    ``x^+ = (I + T A) x^ + T f(x^) + L (y_k - C x^)`` run at period ``T`` against the
    continuous plant ``x' = A x + f(x) + D1 w`` integrated exactly between samples. Roles
    ``A, C, L, T``.
``ui_filter`` (continuous) — reduced-order filter of a descriptor plant with unknown inputs
    (Papers D and E of the Delshad thesis, ``descriptor``, ``uir``): plant
    ``x' = A x + B u + f(x) + D1 w + F nu``, ``y = C x + D2 w + G nu`` (the slow, consistent
    subsystem of ``E zeta' = Abar zeta + ...``, ``zeta = [x; nu]``), filter
    ``z' = N z + L y + Gf u + M f(x^)``, ``zeta^ = J z + E y = [x^; nu^]``. Roles ``A, C, F,
    G, N, L, M, J, E``; optional ``B, Gf, D1, D2``, certified gain ``gamma``.
``filter_error`` (continuous, discrete) — the error system of a filter alone, for the analysis
    theorems that give the filter but not the plant: ``eps' | eps+ = N eps + (L D2 - M D1) w``,
    ``e = J eps + E D2 w`` (the Lipschitz term vanishes on the linear part). Role ``N``;
    optional ``J`` (default I), ``L, M, E, D1, D2, gamma``. The section's ``x0`` is ``eps(0)``.
``obs_control`` (continuous) — observer-based control (Paper F): ``x' = A x + B u + f(x) + E mu``,
    ``x^' = A x^ + B u + f(x^) + L (y - C x^)``, ``u = -K x^``. Roles ``A, B, C, K, L``;
    optional ``E`` and the practical-stability radius ``alpha``.

Examples
--------
>>> import numpy as np
>>> from lmic.simulate.models import make_observer
>>> obs = make_observer("filter_error", "continuous", {"N": -np.eye(2), "J": np.eye(2)})
>>> obs.name, obs.n
('filter_error', 2)

The base class and its helpers are in :mod:`lmic.simulate.custom`, each family in its own module
(:mod:`lmic.simulate.reduced`, :mod:`~lmic.simulate.robust`, :mod:`~lmic.simulate.euler`,
:mod:`~lmic.simulate.ui_filter`, :mod:`~lmic.simulate.filter_error`,
:mod:`~lmic.simulate.obs_control`); this module registers them in
:data:`lmic.simulate.models.MODELS` and re-exports every name it had.
"""

from __future__ import annotations

from lmic.simulate.custom import EXTRA_KEYS, Custom
from lmic.simulate.euler import Euler
from lmic.simulate.filter_error import FilterError
from lmic.simulate.models import MODELS
from lmic.simulate.obs_control import ObsControl
from lmic.simulate.reduced import Reduced
from lmic.simulate.robust import Robust
from lmic.simulate.ui_filter import UIFilter

__all__ = ["Custom", "Reduced", "Robust", "Euler", "UIFilter", "FilterError", "ObsControl", "EXTRA_KEYS"]

for _cls in (Reduced, Robust, Euler, UIFilter, FilterError, ObsControl):
    MODELS[_cls.name] = _cls
