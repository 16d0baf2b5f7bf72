#!/usr/bin/env python3
"""BVH build speed of lenspath against tinybvh's builders, on the same triangles,
interleaved round by round so machine drift hits both alike: its binary-tree
builders (`Build`, `BuildAVX`) and its build of the 8-wide CPU layout
(`BVH8_CPU::Build`, BuildAVX then a conversion), the kind of tree lenspath's
build returns. Twice: on one thread (tinybvh's single-threaded builds), and on
every core (tinybvh's threaded builds, lenspath's parallel one).

tinybvh (https://github.com/jbikker/tinybvh) is taken from the tinybvh-rs crate on
crates.io, which vendors tiny_bvh.h; the peer program is bench/peers/tinybvh_build.cpp
built with g++ -O3 -march=native. Run from anywhere; needs cargo, g++ and network
access to crates.io the first time.

    python3 bench/bvh_build_peers.py [--rounds 5]
"""

import argparse
import itertools
import json
import pathlib
import statistics
import subprocess
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
TINYBVH_CRATE = "tinybvh-rs"
TINYBVH_VERSION = "=0.1.0-beta.3"  # vendors tiny_bvh.h 1.6.8


def tiny_bvh_header(work: pathlib.Path) -> pathlib.Path:
    """Fetches the tinybvh-rs crate into cargo's cache and returns its tiny_bvh.h."""
    project = work / "fetch-tinybvh"
    (project / "src").mkdir(parents=True)
    (project / "src" / "lib.rs").write_text("")
    (project / "Cargo.toml").write_text(
        '[package]\nname = "fetch-tinybvh"\nversion = "0.0.0"\nedition = "2021"\n'
        f'[dependencies]\n{TINYBVH_CRATE} = "{TINYBVH_VERSION}"\n'
    )
    subprocess.run(["cargo", "fetch", "--quiet"], cwd=project, check=True)
    metadata = json.loads(
        subprocess.run(
            ["cargo", "metadata", "--format-version", "1"], cwd=project, check=True, capture_output=True
        ).stdout
    )
    package = next(p for p in metadata["packages"] if p["name"] == TINYBVH_CRATE)
    return pathlib.Path(package["manifest_path"]).parent / "ffi" / "tinybvh" / "tiny_bvh.h"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()

    subprocess.run(["cargo", "build", "--profile", "dist", "--quiet"], cwd=ROOT, check=True)
    lenspath = ROOT / "target" / "dist" / "lenspath"
    with tempfile.TemporaryDirectory() as tmp:
        work = pathlib.Path(tmp)
        header = tiny_bvh_header(work)
        # The peer twice: single-threaded, and with tinybvh's threaded builds.
        peers = {"1 thread": work / "tinybvh_build", "all cores": work / "tinybvh_build_threaded"}
        for peer, define in zip(peers.values(), ([], ["-DPEER_THREADED"]), strict=True):
            subprocess.run(
                [
                    "g++",
                    "-O3",
                    "-march=native",
                    "-std=c++17",
                    *define,
                    f"-I{header.parent}",
                    str(ROOT / "bench" / "peers" / "tinybvh_build.cpp"),
                    "-o",
                    str(peer),
                    "-lpthread",
                ],
                check=True,
            )
        meshes = {"torus knot 1M": ["--procedural", "1000000"]}
        dragon = ROOT.parent / "shared" / "meshes" / "dragon_100k.ply"
        if dragon.exists():
            meshes["dragon 100k"] = [str(dragon)]
        else:
            print(f"skipping the dragon: {dragon} not found")
        for (setting, peer), (mesh_name, source) in itertools.product(peers.items(), meshes.items()):
            threads = ["--threads", "1"] if setting == "1 thread" else []
            ply = work / "mesh.ply"
            # Costs 1:8 (lenspath's default, pbrt's) and 1:1 (tinybvh's default).
            for intersection_cost in (8, 1):
                times: dict[str, list[float]] = {}
                nodes: dict[str, int] = {}
                for _ in range(args.rounds):
                    ours = json.loads(
                        subprocess.run(
                            [
                                lenspath,
                                "bench",
                                "bvh",
                                *source,
                                "--rays",
                                "1000",
                                *threads,
                                "--json",
                                "--intersection-cost",
                                str(intersection_cost),
                                "--save-mesh",
                                ply,
                            ],
                            check=True,
                            capture_output=True,
                            text=True,
                        ).stdout
                    )
                    times.setdefault("lenspath", []).append(ours["build_ms"])
                    nodes["lenspath"] = ours["nodes"]
                    out = subprocess.run(
                        [peer, ply, str(intersection_cost), "1"], check=True, capture_output=True, text=True
                    ).stdout
                    for line in out.splitlines():
                        theirs = json.loads(line)
                        times.setdefault(theirs["builder"], []).append(theirs["build_ms_min"])
                        nodes[theirs["builder"]] = theirs["nodes"]
                triangles = ours["triangles"]
                print(
                    f"\n{mesh_name}, {triangles} triangles, costs 1:{intersection_cost}, {setting} "
                    f"({ours['threads']} for lenspath), {args.rounds} rounds"
                )
                reference = statistics.median(times["lenspath"])
                for builder, ms in times.items():
                    median = statistics.median(ms)
                    print(
                        f"  {builder:18} median {median:7.1f} ms (min {min(ms):7.1f})  "
                        f"{triangles / median / 1e3:5.2f} M tris/s  {nodes[builder]:>8} nodes  "
                        f"time = {median / reference:.2f} x lenspath's"
                    )


if __name__ == "__main__":
    main()
