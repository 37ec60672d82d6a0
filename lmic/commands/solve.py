"""``lmic solve``: compile (or load), solve on a backend, certify.

Forms::

    lmic solve THEOREM SYSTEM [-p k=v]... [--backend B] [--json] [-o CERT.json]
    lmic solve FILE.json|FILE.dat-s [--backend B] [--json] [-o CERT.json]
    lmic solve THEOREM SYSTEM --maximize|--minimize PARAM [--lo a --hi b --xtol t --rtol r] [-o CERT.json]
                                                                                    (lmic.sweep)
    lmic solve THEOREM SYSTEM --sweep PARAM=a:b:n | PARAM=log:a:b:n            (lmic.sweep)

Exit codes (:func:`lmic.outcome.exit_code`, one table for every command): 0 certified,
1 rejected or undecided, 2 bad usage or input (unknown backend, missing solver package, a problem
the backend cannot take), 3 infeasible-certified (a global proof), 4 infeasible-bounded (no
solution with ``||x||_inf <= R`` only), 130 interrupted.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from lmic.commands._common import solve_options  # re-exported: older code imports it from here

__all__ = ["register", "run", "add_solver_options", "solve_options"]


def add_solver_options(p: argparse.ArgumentParser) -> None:
    """Options shared by ``solve`` and ``crosscheck``: tolerance, limits, margin, verbosity."""
    # the values are validated by SolveOptions (lmic.options): bad ones are one line, exit 2
    p.add_argument("--tol", type=float, default=None, help="solver tolerance (default 1e-8)")
    p.add_argument("--max-iter", type=int, default=None, help="iteration limit")
    p.add_argument("--time-limit", type=float, default=None, help="seconds per solve")
    p.add_argument("--margin", type=float, default=None, help="absolute margin imposed on strict LMIs (fixed-margin)")
    p.add_argument(
        "--strict",
        choices=("auto", "max-margin", "fixed-margin"),
        default=None,
        help="strict LMIs of feasibility problems: maximise the margin, impose a fixed one, or auto "
        "(default; docs/backends.md)",
    )
    p.add_argument(
        "--gap",
        type=float,
        default=None,
        help="optimisation problems, default route: stop when the certified enclosure of the optimal value "
        "has this relative gap (default 1e-4); otherwise polish with an interior-point method",
    )
    p.add_argument("--verbose", action="store_true", help="show the solver's own output")


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``solve`` sub-command."""
    from lmic.commands._common import add_param_option

    p = sub.add_parser(
        "solve",
        help="solve and certify a theorem for a system, or an IR / SDPA file",
        description="lmic solve THEOREM SYSTEM [-p k=v]... | FILE.json | FILE.dat-s",
    )
    p.add_argument("target", help="theorem id, or an IR (.json) / SDPA (.dat-s) file")
    p.add_argument("system", nargs="?", default=None, help="system file (with a theorem)")
    add_param_option(p)
    p.add_argument(
        "--backend",
        "-b",
        default=None,
        help="backend (see 'lmic backends'); default: the fastest route that can prove the answer, by shape "
        "and size (docs/backends.md; the chosen route is printed)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("-o", "--output", default=None, help="write the certificate file here")
    p.add_argument("--exact", action="store_true", help="also prove the LMIs exactly")
    p.add_argument(
        "--backoff",
        type=float,
        default=None,
        metavar="REL",
        help="optimisation problems: re-solve with the objective within REL (relative) of the certified "
        "optimum, minimising ||x||_inf (default 1e-3 where the theorem derives gains; 0: off)",
    )
    add_solver_options(p)
    # -- sup and sweep: options and logic live in lmic.sweep (owner: sweep/published) ------------
    from lmic.commands.sweep_cli import add_cli_options

    add_cli_options(p)
    # -- end sup and sweep ------------------------------------------------------------------------
    p.set_defaults(func=run)


def _write_certificate(path: str, result: Any, system: Any) -> None:
    from lmic.certify import write_certificate
    from lmic.system import load_system

    sysobj = load_system(system) if system is not None else None
    write_certificate(
        path,
        result.problem,
        result.solution,
        result.certificate,
        system=sysobj,
        enclosure=getattr(result, "enclosure", None),  # lmic.certify.enclosure
        backoff=getattr(result, "backoff", None),  # lmic.backoff
        unbounded=getattr(result.outcome, "unbounded", None),  # lmic.route_unbounded
    )


def run(args: argparse.Namespace) -> int:
    """Run the pipeline and report; the exit code follows the certificate."""
    from lmic.api import solve
    from lmic.commands._common import parse_params, print_json

    if args.output:
        from lmic.output import check_output_path

        check_output_path(args.output)  # before any work
    # -- sup and sweep (lmic.sweep) ---------------------------------------------------------------
    if getattr(args, "maximize", None) or getattr(args, "minimize", None) or getattr(args, "sweep", None):
        from lmic.commands.sweep_cli import run_cli

        return run_cli(args)
    # -- end sup and sweep ------------------------------------------------------------------------
    params = parse_params(args.param)
    result = solve(
        args.target,
        system=args.system,
        params=params or None,
        backend=args.backend,
        options=solve_options(args),
        exact=args.exact,
        backoff=getattr(args, "backoff", None),
    )
    if args.output:
        if result.certificate is None:
            sys.stderr.write("lmic: no certifier installed: no certificate written\n")
        else:
            _write_certificate(args.output, result, args.system)
    if args.json:
        print_json(result.to_dict())
        return result.exit_code()
    from lmic.present.text import print_result

    print_result(result, args.system, args.output)
    route = getattr(result, "route", None)  # lmic.routes: the backends tried, method, verdict
    if route and route.get("text"):
        print(route["text"])
    # -- optimal-value enclosure (lmic.certify.enclosure); none for a feasibility problem --
    if getattr(result, "enclosure", None) is not None:
        from lmic.certify.enclosure import describe

        for line in describe(result.enclosure):
            print(line)
    if getattr(result, "backoff", None) is not None:
        from lmic.backoff import describe as describe_backoff

        x = result.solution.x
        for line in describe_backoff(result.backoff, None if x is None else float(abs(x).max(initial=0))):
            print(line)
    return result.exit_code()
