"""``lmic compile THEOREM SYSTEM [-p k=v]... -o IR.json``: compile to the IR."""

from __future__ import annotations

import argparse
import sys

from lmic.commands._common import add_param_option, parse_params

__all__ = ["register", "run"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``compile`` sub-command."""
    p = sub.add_parser("compile", help="compile a theorem and a system file into an IR file")
    p.add_argument("theorem", help="theorem id")
    p.add_argument("system", help="system file (YAML or JSON)")
    add_param_option(p)
    p.add_argument("-o", "--output", required=True, help="IR file to write (.json, or .dat-s for SDPA)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Compile and write the IR atomically."""
    from lmic.compile import compile_theorem
    from lmic.ir.io import save_problem
    from lmic.output import check_output_path

    check_output_path(args.output)  # before any work
    prob = compile_theorem(args.theorem, args.system, parse_params(args.param))
    save_problem(prob, args.output)
    sizes = ", ".join(f"{lmi.name} ({lmi.dim}x{lmi.dim})" for lmi in prob.lmis)
    sys.stderr.write(f"lmic: wrote {args.output}: {prob.n} variables, LMIs {sizes}\n")
    return 0
