"""Reductions: passes that turn a problem into one a backend can take, and map answers back.

Like CVXPY's reduction chain (``cvxpy/reductions``), each pass is ``apply(problem) ->
(reduced, inverse)`` and ``inverse(solution) -> solution`` in the original problem's space:

=====================================  ==========================================================
:mod:`lmic.reductions.eliminate`       drop entries of ``x`` no constraint sees (and, for
                                       full-rank solvers, linearly dependent ones)
:mod:`lmic.reductions.strict`          strict LMIs -> closed ones: ``fixed-margin`` or
                                       ``max-margin`` (with the trace normalisation of
                                       scale-free problems)
:mod:`lmic.reductions.precondition`    diagonal congruence ``D F D`` at a reference point
:mod:`lmic.reductions.fix`             fix variables to given values (audits of published points)
:mod:`lmic.reductions.pipeline`        the composition around one backend: eliminate, strict,
                                       the check of inexact infeasibility rays (``solve``)
=====================================  ==========================================================

Backends only lower, call and map (:mod:`lmic.backends`); which passes run, and in which order
of backends, is the solve policy's business (:mod:`lmic.policy`). A pass never decides a
verdict: the certifier judges every answer on the ORIGINAL problem.

Examples
--------
>>> from lmic.reductions import precondition, strict
>>> strict.STRATEGIES
('auto', 'max-margin', 'fixed-margin')
"""
