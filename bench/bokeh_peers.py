#!/usr/bin/env python3
"""Speed of `lenspath bokeh` against OpenCV's cv2.filter2D on the same float image and
kernel, in one run, plus the depth-aware blur. Makes a virtual environment with
opencv-python-headless and numpy from PyPI the first time (bench/.venv-bokeh).

    python3 bench/bokeh_peers.py [--repeat 5]

Cases (docs/bokeh.md, BENCHMARKS.md):
  course   480x360 float RGB, a star mask as large as the image (the course project's
           setting): lenspath FFT, lenspath shift-and-add, cv2.filter2D
  hd       1920x1080 float RGB, 101x101 star mask: lenspath FFT, cv2.filter2D
  depth    1920x1080 pinhole render of cornell-spheres with depths, blurred by depth
           with circles of confusion up to 64 px

lenspath's times are the convolution alone (it prints them), without reading or
writing files; OpenCV's are of filter2D on arrays in memory. Both use every core. That the two
compute the same (black borders, kernel flipped for OpenCV, which correlates) is
checked by crates/lenspath/tests/integration/opencv_agreement.rs:
LENSPATH_PYTHON=$PWD/bench/.venv-bokeh/bin/python cargo test -p lenspath --test integration opencv_agreement::
"""

import argparse
import json
import pathlib
import re
import statistics
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
VENV = ROOT / "bench" / ".venv-bokeh"
LENSPATH = ROOT / "target" / "dist" / "lenspath"


def venv_python() -> pathlib.Path:
    python = VENV / "bin" / "python"
    if not python.exists():
        subprocess.run([sys.executable, "-m", "venv", str(VENV)], check=True)
        subprocess.run([str(python), "-m", "pip", "install", "--quiet", "opencv-python-headless", "numpy"], check=True)
    return python


def lenspath_ms(args: list[str]) -> float:
    out = subprocess.run([str(LENSPATH), *args], check=True, capture_output=True, text=True).stdout
    return float(re.search(r"in ([0-9.]+) ms", out).group(1))


def worker(repeat: int) -> None:
    import cv2
    import numpy as np

    def star(width: int, height: int) -> np.ndarray:
        """A five-pointed star filling a width x height image, white on black."""
        mask = np.zeros((height, width), np.uint8)
        angles = np.pi / 2 + np.arange(10) * np.pi / 5
        radii = np.where(np.arange(10) % 2 == 0, 0.5, 0.22)
        points = np.stack(
            [width / 2 + radii * width * np.cos(angles), height / 2 - radii * height * np.sin(angles)], axis=1
        )
        cv2.fillPoly(mask, [np.round(points).astype(np.int32)], 255)
        return mask

    def lights(width: int, height: int, seed: int) -> np.ndarray:
        """Small lights on a dark background, 8-bit sRGB (BGR for OpenCV)."""
        rng = np.random.default_rng(seed)
        image = np.full((height, width, 3), 25, np.uint8)
        for _ in range(width * height // 7000 + 20):
            centre = (int(rng.integers(width)), int(rng.integers(height)))
            cv2.circle(image, centre, int(rng.integers(1, 4)), (200, 240, 255), -1)
        return image

    def linear(srgb8: np.ndarray) -> np.ndarray:
        v = srgb8.astype(np.float32) / 255.0
        return np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4).astype(np.float32)

    def time_opencv(image: np.ndarray, kernel: np.ndarray) -> tuple[float, np.ndarray]:
        flipped = kernel[::-1, ::-1].copy()
        kh, kw = kernel.shape
        anchor = (kw - 1 - kw // 2, kh - 1 - kh // 2)
        times = []
        for _ in range(repeat):
            start = cv2.getTickCount()
            out = cv2.filter2D(image, -1, flipped, anchor=anchor, borderType=cv2.BORDER_CONSTANT)
            times.append((cv2.getTickCount() - start) / cv2.getTickFrequency() * 1e3)
        return statistics.median(times), out

    results = {"opencv": cv2.__version__, "threads": cv2.getNumThreads()}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        for case, (width, height), mask in [
            ("course", (480, 360), star(480, 360)),
            ("hd", (1920, 1080), star(101, 101)),
        ]:
            image8 = lights(width, height, 1)
            cv2.imwrite(str(tmp / "in.png"), image8)
            cv2.imwrite(str(tmp / "mask.png"), mask)
            kernel = mask.astype(np.float32) / float(mask.sum())
            common = [
                "bokeh",
                str(tmp / "in.png"),
                "--mask",
                str(tmp / "mask.png"),
                "--edges",
                "black",
                "--out",
                str(tmp / "out.exr"),
            ]
            fft = statistics.median(lenspath_ms([*common, "--method", "fft"]) for _ in range(repeat))
            opencv, _ = time_opencv(linear(image8)[:, :, ::-1].copy(), kernel)
            row = {"lenspath_fft_ms": fft, "opencv_filter2d_ms": opencv}
            if case == "course":
                row["lenspath_direct_ms"] = lenspath_ms([*common, "--method", "direct"])
            results[case] = row
        # Depth-aware blur of a real render with depths.
        exr = tmp / "pinhole.exr"
        subprocess.run(
            [str(LENSPATH), "render", "--camera", "pinhole", "--res", "1920x1080", "--spp", "4", "--out", str(exr)],
            check=True,
            capture_output=True,
        )
        depth_args = [
            "bokeh",
            str(exr),
            "--mask",
            "blades:6",
            "--focus-distance",
            "3.0",
            "--aperture-radius",
            "0.0647",
            "--fov",
            "40",
            "--out",
            str(tmp / "dof.exr"),
        ]
        results["depth"] = {"lenspath_ms": statistics.median(lenspath_ms(depth_args) for _ in range(repeat))}
    print(json.dumps(results, indent=2))
    course, hd = results["course"], results["hd"]
    print()
    print("| case | lenspath FFT | lenspath shift-and-add | cv2.filter2D | FFT vs filter2D |")
    print("|---|---|---|---|---|")
    fft, direct, opencv = course["lenspath_fft_ms"], course["lenspath_direct_ms"], course["opencv_filter2d_ms"]
    print(
        f"| 480x360, star mask as large as the image | {fft:.1f} ms | {direct:.0f} ms ({direct / fft:.0f}x) | "
        f"{opencv:.1f} ms | {opencv / fft:.2f}x faster |"
    )
    print(
        f"| 1920x1080, 101x101 star | {hd['lenspath_fft_ms']:.1f} ms | | {hd['opencv_filter2d_ms']:.1f} ms | "
        f"{hd['opencv_filter2d_ms'] / hd['lenspath_fft_ms']:.2f}x faster |"
    )
    print(f"| 1920x1080 by depth, CoC up to 64 px | {results['depth']['lenspath_ms']:.0f} ms | | | |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        worker(args.repeat)
        return
    subprocess.run(["cargo", "build", "--profile", "dist", "--quiet"], cwd=ROOT, check=True)
    python = venv_python()
    subprocess.run([str(python), __file__, "--worker", "--repeat", str(args.repeat)], check=True)


if __name__ == "__main__":
    main()
