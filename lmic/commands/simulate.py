"""``lmic simulate THEOREM SYSTEM [-p k=v]... [--backend B] [-o plot.png] [--json]``.

Solves and certifies the theorem for the system, then simulates the plant and the observer the
theorem designs (its ``t.observer(...)`` declaration, with the certified gains) as the system
file's ``simulation:`` section says, prints the final estimation error and whether it decayed,
and with ``-o`` writes the figure (PNG; written atomically, and only after a successful run).

Where the theorem certifies a number (an L2 gain, a decay rate: the observer roles ``gamma``,
``decay``), the run measures it on trajectories (:mod:`lmic.simulate.certificate`) and prints
both; a measured value beyond the certified one is a red flag and exit code 1.

Exit codes: 0 simulated with certified gains; 1 or 3 when the gains are not certified (the
solve's own code: nothing is simulated); 2 for bad input — no ``simulation:`` section, an
unknown key, a forbidden token in an expression, a theorem without an observer, or a state that
blows up (the message names the time).
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

__all__ = ["register", "run"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``simulate`` sub-command."""
    from lmic.commands._common import add_param_option

    p = sub.add_parser(
        "simulate",
        help="simulate the plant and the certified observer (system file 'simulation:' section)",
        description="lmic simulate THEOREM SYSTEM [-p k=v]... [--backend B] [-o plot.png] [--json]",
    )
    p.add_argument("theorem", help="theorem id (it must declare its observer)")
    p.add_argument("system", help="system file with a 'simulation:' section")
    add_param_option(p)
    p.add_argument("--backend", "-b", default="clarabel", help="backend (see 'lmic backends')")
    p.add_argument("-o", "--output", default=None, help="write the figure here (PNG)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


def _check_output(path: str | None) -> None:
    """Fail early (before solving) on an output path that cannot be written."""
    from lmic.output import check_output_path

    if path is not None:
        check_output_path(path)


def simulation_section(system: Any) -> tuple[Any, Any]:
    """The loaded system and its checked ``simulation:`` section (keys and types only)."""
    from lmic.errors import DataError
    from lmic.simulate.run import check_section
    from lmic.system import load_system

    sysobj = load_system(system)
    section = sysobj.raw.get("simulation")
    if section is None:
        raise DataError(f"{sysobj.label}: has no 'simulation:' section (see schemas/simulation.schema.json)")
    check_section(section, f"{sysobj.label}: simulation")
    return sysobj, section


def run(args: argparse.Namespace) -> int:
    """Solve, simulate, report the final error; write the figure with ``-o``."""
    from lmic.api import solve
    from lmic.commands._common import parse_params, print_json, write_atomic
    from lmic.simulate.plot import plot_png
    from lmic.simulate.run import simulate

    _check_output(args.output)
    params = parse_params(args.param)
    sysobj, _section = simulation_section(args.system)
    result = solve(args.theorem, system=sysobj, params=params or None, backend=args.backend)
    if result.exit_code() != 0:
        sys.stderr.write(
            f"lmic: {args.theorem}: status {result.status}, verdict {result.verdict}: "
            "no certified gains, nothing simulated\n"
        )
        if args.json:
            print_json(
                {"theorem": args.theorem, "status": result.status, "verdict": result.verdict, "simulation": None}
            )
        return result.exit_code()
    observer, traj = simulate(result.problem, result.solution.x, sysobj)
    png = plot_png(traj, title=args.theorem) if args.output else None
    if png is not None:
        write_atomic(args.output, lambda fh: fh.write(png), mode="wb")
    summary = traj.summary()
    violated = [c for c in traj.checks if c.get("ok") is False]
    if args.json:
        print_json(
            {
                "theorem": args.theorem,
                "system": args.system,
                "backend": result.backend,
                "status": result.status,
                "verdict": result.verdict,
                "observer": {"model": observer.name, "time": observer.time, "roles": observer.names},
                "simulation": summary,
                "plot": args.output,
                "certificate_violated": bool(violated),
            }
        )
        return 1 if violated else 0
    out = sys.stdout
    out.write(f"theorem    {args.theorem} {args.system}\n")
    out.write(f"solve      {result.backend}: {result.status}, {result.verdict}\n")
    out.write(f"observer   {observer.name} ({observer.time} time), n = {observer.n}, p = {observer.p}\n")
    extra = f", {summary['samples']} samples" if summary["samples"] is not None else ""
    out.write(f"horizon    {summary['horizon']:.6g} ({summary['points']} points{extra})\n")
    out.write(f"error      initial {summary['initial_error']:.4g}, peak {summary['peak_error']:.4g}\n")
    verdict = "decayed" if summary["decayed"] else "did NOT decay"
    out.write(f"final      |x - xhat| = {summary['final_error']:.4g} ({verdict})\n")
    for c in traj.checks:
        mark = {True: "holds", False: "VIOLATED", None: "(informative)"}[c.get("ok")]
        out.write(
            f"certified  {c['property']}: certified {c['certified']:.6g}, measured {c['measured']:.6g} {mark}\n"
            f"           {c['detail']}\n"
        )
    if violated:
        sys.stderr.write(
            "lmic: RED FLAG: the trajectory violates what the theorem certified "
            f"({', '.join(c['property'] for c in violated)}): the theorem, its transcription or the "
            "certificate is wrong\n"
        )
    if args.output:
        out.write(f"wrote      {args.output}\n")
    return 1 if violated else 0
