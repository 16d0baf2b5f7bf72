"""What the peer benchmarks share: their virtual environment, the machine they run on, the
sample-count sweeps and their reading at a time, and a PLY reader."""

from __future__ import annotations

import os
import platform
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

# numpy's OpenBLAS threads spin after each call, taking a core from the
# renderers being timed (3% of samples on 2 cores); no benchmark needs them.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

ROOT = Path(__file__).resolve().parents[2]
VENV = ROOT / "bench" / ".venv-peers"

_PLY_TYPES = {"char": "i1", "uchar": "u1", "short": "<i2", "ushort": "<u2", "int": "<i4", "uint": "<u4"}
_PLY_TYPES |= {"float": "<f4", "double": "<f8"}


def in_venv(packages: list[str], install_lenspath: bool = False) -> None:
    """Reruns the calling script inside bench/.venv-peers with `packages` (and this
    lenspath, by `pip install .`) installed; returns at once when already there."""
    if Path(sys.prefix).resolve() == VENV.resolve():
        return
    python = VENV / "bin" / "python"
    if not python.exists():
        subprocess.run([sys.executable, "-m", "venv", str(VENV)], check=True)
    subprocess.run([str(python), "-m", "pip", "install", "-q", *packages], check=True)
    if install_lenspath:
        subprocess.run([str(python), "-m", "pip", "install", "-q", str(ROOT)], check=True)
    os.execv(str(python), [str(python), *sys.argv])


# Widest first: /proc/cpuinfo's flag, and the name printed.
_VECTOR_EXTENSIONS = [("avx512f", "AVX-512"), ("avx2", "AVX2"), ("avx", "AVX")]


def machine() -> str:
    """The CPU the figures are taken on and the widest vector extension it has. The peers'
    kernels (Embree's, Mitsuba's LLVM JIT) pick theirs at run time and use AVX-512 where it
    is; lenspath's stop at AVX2. So a ratio holds for that kind of machine (BENCHMARKS.md,
    forty-sixth session: Mitsuba gained far more than lenspath on an AVX-512 machine)."""
    model, flags = platform.processor() or "unknown CPU", set()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            key, _, value = line.partition(":")
            if key.strip() == "model name":
                model = value.strip()
            elif key.strip() == "flags":
                flags = set(value.split())
    except OSError:
        pass
    widest = next((name for flag, name in _VECTOR_EXTENSIONS if flag in flags), "no AVX")
    return f"{model}, {os.cpu_count()} CPUs, {widest}"


def doubling_sweep(measure, longest_s: float) -> list[tuple[int, float, float]]:
    """(spp, seconds, MSE) at 1, 2, 4, ... samples per pixel, `measure(spp)` giving a render's
    seconds and MSE, until a render takes longer than `longest_s` (that render included):
    `interleaved_sweeps` for one renderer and one run."""
    return interleaved_sweeps({"": lambda spp, _run: measure(spp)}, longest_s, 1)[""]


def interleaved_sweeps(
    measures: dict[str, Callable[[int, int], tuple[float, float]]], longest_s: float, runs: int
) -> dict[str, list[tuple[int, float, float]]]:
    """`doubling_sweep` for several renderers at once, their renders interleaved: at 1, 2, 4,
    ... samples per pixel each renderer still sweeping renders once in turn, `runs` times
    round (`measures[name](spp, run)` gives a render's seconds and MSE), so a slower or faster
    stretch of a shared machine falls on all of them alike rather than on whichever renderer's
    sweep it met. A renderer's row at each count is its median time and mean MSE; it stops
    after the count whose median took longer than `longest_s`."""
    import statistics

    rows: dict[str, list[tuple[int, float, float]]] = {name: [] for name in measures}
    active, spp = list(measures), 1
    while active:
        taken: dict[str, list[tuple[float, float]]] = {name: [] for name in active}
        for run in range(runs):
            for name in active:
                taken[name].append(measures[name](spp, run))
        for name in active:
            seconds = statistics.median(t for t, _ in taken[name])
            mse = statistics.fmean(e for _, e in taken[name])
            rows[name].append((spp, seconds, mse))
            label = f"{name:24s} " if name else ""
            print(f"    {label}{spp:6d} spp {seconds:8.3f} s  MSE {mse:.3e}", flush=True)
        active = [name for name in active if rows[name][-1][1] <= longest_s]
        spp *= 2
    return rows


def at_time(rows: list[tuple[int, float, float]], seconds: float) -> float | None:
    """From a renderer's (spp, seconds, MSE) rows in order of time, the MSE at `seconds` by
    log-log interpolation between the two renders around it (None outside them)."""
    import math

    for (_, t0, e0), (_, t1, e1) in zip(rows, rows[1:], strict=False):
        if t0 <= seconds <= t1:
            f = (math.log(seconds) - math.log(t0)) / (math.log(t1) - math.log(t0))
            return math.exp(math.log(e0) + f * (math.log(e1) - math.log(e0)))
    return None


def read_binary_ply(path: Path):
    """Vertices (N x 3 float32) and triangles (M x 3 int32) of a binary little-endian PLY
    whose faces are all triangles, whatever other properties it carries."""
    import numpy as np

    data = path.read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    elements: list[tuple[str, int, list[tuple[str, ...]]]] = []
    for line in data[:end].decode("ascii").splitlines():
        words = line.split()
        if words[:1] == ["format"] and words[1] != "binary_little_endian":
            raise ValueError(f"{path}: only binary_little_endian PLY is read here, not {words[1]}")
        if words[:1] == ["element"]:
            elements.append((words[1], int(words[2]), []))
        elif words[:1] == ["property"]:
            elements[-1][2].append(tuple(words[1:]))
    offset, arrays = end, {}
    for name, count, properties in elements:
        fields = []
        for p in properties:
            if p[0] == "list":  # the faces: a uchar count of 3, then three indices
                fields += [(p[3] + "_n", _PLY_TYPES[p[1]]), (p[3], _PLY_TYPES[p[2]], 3)]
            else:
                fields.append((p[1], _PLY_TYPES[p[0]]))
        records = np.frombuffer(data, np.dtype(fields), count, offset)
        offset += records.nbytes
        arrays[name] = records
    vertex, face = arrays["vertex"], arrays["face"]
    if not (face["vertex_indices_n"] == 3).all():
        raise ValueError(f"{path}: not all faces are triangles")
    vertices = np.stack([vertex["x"], vertex["y"], vertex["z"]], axis=1).astype(np.float32)
    return vertices, face["vertex_indices"].astype(np.int32)
