"""``lmic report THEOREM SYSTEM -o report.html [-p k=v]... [--backend B] [--backends a,b]``.

Writes one self-contained HTML page (KaTeX, fonts and the figure inlined; it opens offline):
the theorem as printed, the system, the solution and gains, the certificate with margins, the
cross-check table and the simulation figure (when the theorem declares an observer and the
system file has a ``simulation:`` section). The file is written atomically.

Exit codes: the solve's (0 certified, 3 infeasible, 1 rejected or failed: the report is written
in every one of these cases); 2 for bad input (nothing written).
"""

from __future__ import annotations

import argparse
import sys

__all__ = ["register", "run"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``report`` sub-command."""
    from lmic.commands._common import add_param_option

    p = sub.add_parser(
        "report",
        help="write a self-contained HTML report: theorem, system, gains, certificate, cross-check, simulation",
        description="lmic report THEOREM SYSTEM -o report.html [-p k=v]... [--backend B] [--backends a,b,...]",
    )
    p.add_argument("theorem", help="theorem id")
    p.add_argument("system", help="system file")
    p.add_argument("-o", "--output", required=True, help="the HTML file to write")
    add_param_option(p)
    p.add_argument("--backend", "-b", default=None, help="main solve: this backend alone (default: the policy)")
    p.add_argument("--backends", default=None, help="comma-separated cross-check backends (default: every available)")
    p.add_argument("--no-crosscheck", action="store_true", help="leave the cross-check out")
    p.add_argument("--no-simulation", action="store_true", help="leave the simulation out")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Build the report and write it; the exit code follows the certificate."""
    from lmic.backends.registry import get_backend
    from lmic.commands._common import backend_names, parse_params
    from lmic.commands.simulate import _check_output
    from lmic.report import build_report

    _check_output(args.output)
    names = backend_names(args.backends)
    if args.backend is not None:
        get_backend(args.backend)
    report = build_report(
        args.theorem,
        args.system,
        params=parse_params(args.param) or None,
        backend=args.backend,
        crosscheck_backends=names,
        run_crosscheck=not args.no_crosscheck,
        run_simulation=not args.no_simulation,
    )
    report.write(args.output)
    out = sys.stdout
    res = report.result
    out.write(f"theorem    {args.theorem} {args.system}\n")
    out.write(f"solve      {res.backend}: {res.status}, {res.verdict}\n")
    if report.crosscheck is not None:
        agree = "agree" if report.crosscheck.agree else "DISAGREE"
        out.write(f"crosscheck {len(report.crosscheck.results)} backends, {agree}\n")
    if report.trajectory is not None:
        traj = report.trajectory
        verdict = "decayed" if traj.decayed else "did NOT decay"
        out.write(f"simulation final error {traj.final_error:.4g} ({verdict})\n")
    elif report.simulation_note:
        out.write(f"simulation {report.simulation_note}\n")
    size = len(report.html.encode("utf-8"))
    out.write(f"wrote      {args.output} ({size / 1024:.0f} KiB)\n")
    return report.exit_code()
