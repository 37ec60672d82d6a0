"""The long fuzzing campaign over every reader of lmic (#12): crashes, hangs, memory.

Usage::

    PYTHONPATH=.:plugins python benchmarks/fuzz.py [--runs 400] [--seed 1] [--timeout 20]

For each reader (system file, ``simulation:`` section, SDPA file, IR JSON, certificate JSON)
it builds mutants of a real file (byte edits: digit runs, brackets, YAML anchors and aliases,
NaN, control bytes, duplicated spans) plus the catalogue of bombs of the issue (alias bombs,
deep nesting, 5000-digit numbers, huge declared sizes). Each input is read in a worker
subprocess limited to 4 GB of address space (``RLIMIT_AS``): a ``MemoryError`` or a worker
killed by the limit counts as ">4 GB", a read taking longer than ``--timeout`` seconds as a
hang, any exception other than :class:`lmic.errors.LmicError` (the one-line, exit-code-2
rejection) as a crash. The workers run batches in-process (a fresh subprocess per batch and
after every failure) so that thousands of runs take minutes, not hours.

Prints one table: reader, runs, read, rejected, crashes, hangs, >4 GB.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SYSTEM = (ROOT / "examples" / "qib.thm1.flexible-joint.yaml").read_bytes()
SDPA = (
    Path("/work/shared/sdplib/control1.dat-s").read_bytes()
    if Path("/work/shared/sdplib/control1.dat-s").exists()
    else b"2\n2\n2 -1\n1.0 -2.5\n0 1 1 1 1.0\n1 1 1 1 1.0\n1 1 1 2 0.5\n2 1 2 2 1.0\n2 2 1 1 3.0\n"
)

CHUNKS = [
    b"9", b"9" * 5000, b"[", b"{", b"]", b"}", b"-", b".nan", b".inf", b"&a ", b"*a", b"\x00", b"\xff",
    b"e999", b"\n", b": ", b"'", b'"', b"1e-400", "١٢".encode(), b"!!python/object:os.system ", b"<<: *a\n",
    b"-1000000000", b"9223372036854775808", b"50000", b"NaN", b"Infinity", b"1" * 100000 + b"x",
]  # fmt: skip

#: largest mutant (bytes): the bombs are small files; big ones only fill the disk
MAX_MUTANT = 1_000_000

WORKER = r"""
import json, sys, resource, signal, traceback
resource.setrlimit(resource.RLIMIT_AS, (4 * 2**30, 4 * 2**30))
from lmic.errors import LmicError
kind, paths, timeout = sys.argv[1], sys.argv[2:-1], int(sys.argv[-1])

class Hang(BaseException):
    pass

def alarm(*_):
    raise Hang()

signal.signal(signal.SIGALRM, alarm)

def read(kind, path):
    if kind == "system":
        from lmic.system import load_system
        load_system(path)
    elif kind == "simulation":
        from lmic.system import load_system
        from lmic.simulate.run import check_section
        s = load_system(path)
        if "simulation" in s.raw:
            check_section(s.raw["simulation"], "simulation")
    elif kind == "sdpa":
        from lmic.ir.sdpa import read_sdpa
        read_sdpa(path)
    elif kind == "ir":
        from lmic.ir.jsonio import load_problem_json
        load_problem_json(path)
    elif kind in ("certificate", "enclosure"):
        from lmic.certify.certificate import audit_certificate
        audit_certificate(path)

for path in paths:
    signal.alarm(timeout)
    try:
        read(kind, path)
        out = "read"
    except LmicError:
        out = "rejected"
    except Hang:
        out = "hang"
    except MemoryError:
        out = "memory"
    except RecursionError:
        out = "crash"
    except Exception as err:
        out = "crash:" + type(err).__name__ + ": " + str(err)[:100]
    finally:
        signal.alarm(0)
    print(json.dumps([path, out]), flush=True)
"""


def mutate(data: bytes, rng: random.Random) -> bytes:
    out = bytearray(data)
    for _ in range(rng.randint(1, 4)):
        i = rng.randrange(len(out) + 1)
        chunk = rng.choice(CHUNKS)
        op = rng.randrange(4)
        if op == 0:
            out[i : i + 1] = chunk
        elif op == 1:
            del out[i : i + rng.randint(1, 40)]
        elif op == 2:
            times = rng.choice([1, 10, 1000])
            out[i:i] = chunk * max(1, min(times, MAX_MUTANT // max(1, len(chunk))))
        else:
            out[i:i] = out[max(0, i - 60) : i] * rng.choice([1, 100])
    return bytes(out[: max(MAX_MUTANT, len(data))])


def bombs(kind: str) -> list[bytes]:
    alias = b"lmic: 1\na: &a [x, x, x, x, x, x, x, x, x, x]\n" + b"".join(
        f"{c}: &{c} [".encode() + b", ".join([f"*{p}".encode()] * 10) + b"]\n"
        for p, c in zip("abcdefgh", "bcdefghi", strict=True)
    )
    if kind in ("system", "simulation"):
        head = SYSTEM.split(b"simulation:")[0]
        return [
            alias + b"data: {A: [[1]]}\n",
            b"lmic: 1\ndata:\n  A: " + b"[" * 100000 + b"]" * 100000 + b"\n",
            b"lmic: 1\ndata:\n  A: [[" + b"9" * 5000 + b"]]\n",
            b"lmic: true\ndata: {A: [[1]]}\n",
            head + b"simulation:\n  x0: [1, 0, 0, 0]\n  horizon: .nan\n",
            head + b"simulation:\n  x0: [1, 0, 0, 0]\n  horizon: " + b"9" * 5000 + b"\n",
            head + b"simulation:\n  x0: [1, 0, 0, 0]\n  horizon: 2\n  sampling: {max: .nan}\n",
            head + b"simulation:\n  nonlinearity: {1: x1}\n  x0: [1, 0, 0, 0]\n  horizon: 2\n",
        ]
    if kind == "sdpa":
        return [
            b"1\n1\n50000\n1.0\n1 1 1 1 1.0\n",
            b"1\n1\n-1000000000\n1.0\n1 1 1 1 1.0\n",
            b"1\n1\n9223372036854775808\n1.0\n",
            b"1\n1\n2\n1.0\n1 1 1 1 " + b"1" * 5000 + b"\n",
            b"1\n1\n2\n1.0\n1 1 1 1 " + b"1" * 100000 + b"x\n",
            b'* lmic: {"c0": ' + b"9" * 5000 + b"}\n1\n1\n1\n1.0\n",
            b"* lmic: " + b"[" * 100000 + b"\n1\n1\n1\n1.0\n",
        ]
    if kind == "ir":
        return [
            b'{"lmic_ir": 1, "x": ' + b"[" * 100000 + b"]" * 100000 + b"}",
            b'{"lmic_ir": ' + b"1" * 5000 + b"}",
        ]
    return [b'{"lmic_certificate": 1, "x": ' + b"[" * 100000 + b"]" * 100000 + b"}"]


def seeds(folder: Path) -> dict[str, tuple[bytes, str]]:
    """A real file per reader (and its suffix)."""
    from lmic.certify.certificate import write_certificate
    from lmic.compile import compile_theorem
    from lmic.ir.jsonio import problem_to_json
    from lmic.system import load_system

    system = load_system(ROOT / "examples" / "qib.thm1.flexible-joint.yaml")
    prob = compile_theorem("qib.thm1", system)
    from lmic.api import solve

    r = solve("qib.thm1", system=str(ROOT / "examples" / "qib.thm1.flexible-joint.yaml"))
    cert = folder / "seed-cert.json"
    write_certificate(cert, r.problem, r.solution, r.certificate, embed_ir=True)
    out = {
        "system": (SYSTEM, ".yaml"),
        "simulation": (SYSTEM, ".yaml"),
        "sdpa": (SDPA, ".dat-s"),
        "ir": (problem_to_json(prob).encode(), ".json"),
        "certificate": (cert.read_bytes(), ".json"),
    }
    control1 = Path("/work/shared/sdplib/control1.dat-s")
    if control1.exists():  # a certificate with an optimal-value enclosure (dual point) as well
        e = solve(str(control1), backend="clarabel")
        enc = folder / "seed-enclosure.json"
        write_certificate(enc, e.problem, e.solution, e.certificate, enclosure=e.enclosure)
        out["enclosure"] = (enc.read_bytes(), ".json")
    return out


def run_batch(kind: str, paths: list[str], timeout: int) -> dict[str, str]:
    """Outcome per path; restarts the worker after a path that kills it."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), str(ROOT / "plugins")]))
    out: dict[str, str] = {}
    todo = list(paths)
    while todo:
        proc = subprocess.Popen(
            [sys.executable, "-c", WORKER, kind, *todo, str(timeout)],
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            text=True,
            env=env,
        )
        try:
            stdout, _ = proc.communicate(timeout=timeout * len(todo) + 60)
        except subprocess.TimeoutExpired:
            proc.kill()
            stdout, _ = proc.communicate()
        for line in stdout.splitlines():
            path, result = json.loads(line)
            out[path] = result
        rest = [p for p in todo if p not in out]
        if rest:  # the worker died on rest[0] (killed by the memory limit, or a segfault)
            out[rest[0]] = "memory" if proc.returncode in (-9, -6, 137) else f"crash:exit {proc.returncode}"
            rest = rest[1:]
        todo = rest
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=400, help="mutants per reader (plus the bombs)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--timeout", type=int, default=20, help="seconds before a read counts as a hang")
    ap.add_argument("--batch", type=int, default=100)
    args = ap.parse_args()
    rng = random.Random(args.seed)
    rows = []
    examples: list[str] = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        base = seeds(folder)
        for kind, (data, suffix) in base.items():
            t0 = time.perf_counter()
            n_inputs = len(bombs(kind)) + args.runs
            results: dict[str, str] = {}
            for k in range(0, n_inputs, args.batch):
                paths = []
                for i in range(k, min(n_inputs, k + args.batch)):
                    blob = bombs(kind)[i] if i < len(bombs(kind)) else mutate(data, rng)
                    p = folder / f"{kind}-{i}{suffix}"
                    p.write_bytes(blob)
                    paths.append(str(p))
                results.update(run_batch(kind, paths, args.timeout))
                for path in paths:
                    os.unlink(path)
            counts = {"read": 0, "rejected": 0, "crash": 0, "hang": 0, "memory": 0}
            for path, res in results.items():
                key = res.split(":")[0]
                counts[key] += 1
                if key != "read" and key != "rejected" and len(examples) < 10:
                    examples.append(f"{kind} {Path(path).name}: {res}")
            rows.append((kind, n_inputs, counts, time.perf_counter() - t0))
    print(
        f"{'reader':<12} {'runs':>6} {'read':>6} {'rejected':>9} {'crashes':>8} {'hangs':>6} {'>4 GB':>6} {'time':>8}"
    )
    total = {"runs": 0, "crash": 0, "hang": 0, "memory": 0}
    for kind, n, c, dt in rows:
        cells = (n, c["read"], c["rejected"], c["crash"], c["hang"], c["memory"], f"{dt:.0f}s")
        print(f"{kind:<12}" + "".join(f" {v:>8}" for v in cells))
        total["runs"] += n
        for k in ("crash", "hang", "memory"):
            total[k] += c[k]
    print(
        f"{'total':<12} {total['runs']:>6} {'':>6} {'':>9} {total['crash']:>8} {total['hang']:>6} {total['memory']:>6}"
    )
    for line in examples:
        print("  " + line)


if __name__ == "__main__":
    main()
