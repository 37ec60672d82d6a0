"""lmic.present.text: what ``lmic solve`` prints about the objective and the ways further.

A newcomer's discrete-time bounded-real lemma on an unstable plant (eigenvalue 1.1) printed
``objective 63112.37`` for a problem it had just shown infeasible, and suggested ``--exact``
after the exact proof had run and failed; a certified answer whose optimal value is enclosed
below the returned point's objective printed that objective without saying so.
"""

from __future__ import annotations

import io

from certify_helpers import inline_dbrl
from rich.console import Console

import lmic.api
from lmic.present.text import print_result


def _text(result) -> str:
    out = io.StringIO()
    print_result(result, console=Console(file=out, width=200, highlight=False, soft_wrap=True))
    return out.getvalue()


def test_an_infeasible_answer_prints_no_objective_and_no_exact_after_the_exact_proof():
    system = {"lmic": 1, "data": {"A": [[1.1, 0.0], [0.3, 0.5]], "B": [[1.0], [0.0]], "C": [[1.0, 1.0]]}}
    r = lmic.api.solve(inline_dbrl, system, exact=True)
    assert r.verdict.startswith("infeasible")
    text = _text(r)
    assert "objective" not in text
    assert "--exact" not in r.outcome.reason
    assert "theorem  Discrete-time bounded-real lemma (de Souza & Xie (1992))" in text


def test_an_objective_outside_the_enclosure_says_whose_it_is():
    system = {"lmic": 1, "data": {"A": [[0.5, 0.2], [0.0, 0.3]], "B": [[1.0], [0.5]], "C": [[1.0, 0.0]]}}
    r = lmic.api.solve(inline_dbrl, system)
    assert r.verdict == "certified" and r.enclosure["lower"] <= r.objective
    assert "the returned point's" not in _text(r)
    r.enclosure["upper"] = r.objective * (1 - 1e-3)  # as when the upper end is a restored point
    assert f"objective  {r.objective:.10g} (the returned point's; the optimal value is enclosed below)" in _text(r)


def test_a_checks_number_says_what_it_is():
    """A Hurwitz check's number is the spectral abscissa, not a margin: the table says so."""
    system = {"lmic": 1, "data": {"A": [[-1.0, 0.5], [0.0, -2.0]]}}
    text = _text(lmic.api.solve("thesis.lyapunov", system))
    assert "min margin / value" in text
    assert "check hurwitz (spectral abscissa)" in text
