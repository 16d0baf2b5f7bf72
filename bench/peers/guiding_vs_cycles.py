#!/usr/bin/env python3
"""Path guiding at equal time: lenspath's path tracer and guided path tracer against Blender
Cycles with its path guiding (Intel Open PGL) on, the same scene file built in both (issue 33).

    python3 bench/peers/guiding_vs_cycles.py [--scene scenes/glass-and-gold.toml] [--res 320 240]
                                             [--budgets 2 8] [--ref-spp 2048] [--json F]

The scene file (quads, spheres, diffuse, dielectric and conductor materials, emissive quads, a
constant environment) is read here and rebuilt in Cycles: lenspath's y-up coordinates turned to
Blender's z-up, each sphere a smooth 128 x 64 UV sphere, an emissive quad emitting from its front
only, glass as the Glass BSDF (roughness 0), a conductor as the Metallic BSDF with the physical
conductor Fresnel (GGX roughness = sqrt(alpha); a measured metal by its RGB n and k at 650, 550
and 450 nm). Both render through a pinhole camera with the file's `fov_y_deg`, a one-pixel box
filter, the file's max depth, on every core, no denoising, no adaptive sampling, no clamping.
lenspath renders with the CLI (`target/dist/lenspath`, built here by cargo) and its render
time (guide training included); Cycles through `bpy` and the wall time of
`bpy.ops.render.render` after an untimed warm-up render (its guide trains during the render),
with path guiding on and, for comparison, off.

Each renderer renders at 1, 2, 4, ... samples per pixel until a render takes longer than the
largest budget, and each image's mean squared error is taken against that renderer's own
converged render (`--ref-spp`, another seed): the two differ in their materials' colours
(lenspath is spectral, Cycles RGB) and in the spheres' tessellation, so the figure compared is
each one's noise, what a user waits on. At each budget the error is read off each curve by
log-log interpolation; the ratio lenspath / Cycles below 1 means lenspath's image is closer to
converged at that time. The two references' mean brightness is printed beside, as a check that
the scenes agree.

Runs in bench/.venv-peers (numpy, bpy, OpenEXR), as the other peer benchmarks do.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

from common import ROOT, at_time, doubling_sweep, in_venv

LENSPATH = ROOT / "target" / "dist" / "lenspath"
CACHE = ROOT / "target" / "bench-references"
# Gold's n and k at 650, 550 and 450 nm, as scenes/glass-and-gold.toml gives them: what Cycles
# gets for `metal = "Au"` (it takes RGB).
METALS = {"Au": ([0.143, 0.374, 1.442], [3.983, 2.385, 1.603])}


def read_exr(path: Path):
    """The RGB channels of an EXR as an (H, W, 3) float64 array, whatever its layer naming."""
    import numpy as np
    import OpenEXR

    channels = OpenEXR.File(str(path)).channels()
    if "RGB" in channels or "RGBA" in channels:
        pixels = np.asarray(channels.get("RGB", channels.get("RGBA")).pixels, dtype=np.float64)
        return pixels[..., :3]
    names = {name.split(".")[-1]: c for name, c in channels.items()}
    return np.stack([np.asarray(names[c].pixels, dtype=np.float64) for c in "RGB"], axis=-1)


def to_blender(p) -> tuple[float, float, float]:
    """lenspath's y-up point or vector in Blender's z-up axes (a rotation: handedness kept)."""
    x, y, z = (float(v) for v in p)
    return (x, -z, y)


def rgb(value) -> tuple[float, float, float, float]:
    """A scene file's colour (a number or three) as Blender's RGBA."""
    r, g, b = (value, value, value) if isinstance(value, (int, float)) else value
    return (float(r), float(g), float(b), 1.0)


def build_cycles(scene_file: dict, res: tuple[int, int], max_depth: int) -> None:
    """Replaces Blender's scene with `scene_file`'s, set up for Cycles as the module says."""
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    cycles = scene.cycles
    cycles.device = "CPU"
    cycles.use_adaptive_sampling = False
    cycles.use_denoising = False
    for bounces in ("max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces"):
        setattr(cycles, bounces, max_depth)
    cycles.transparent_max_bounces = max_depth
    cycles.volume_bounces = 0
    cycles.sample_clamp_direct = 0.0
    cycles.sample_clamp_indirect = 0.0
    cycles.blur_glossy = 0.0
    cycles.caustics_reflective = True
    cycles.caustics_refractive = True
    cycles.pixel_filter_type = "BOX"
    cycles.filter_width = 1.0
    cycles.use_guiding = True
    cycles.use_surface_guiding = True
    scene.render.threads_mode = "AUTO"
    scene.render.resolution_x, scene.render.resolution_y = res
    scene.render.resolution_percentage = 100
    scene.view_settings.view_transform = "Standard"
    settings = scene.render.image_settings
    settings.file_format = "OPEN_EXR"
    settings.color_depth = "32"
    settings.exr_codec = "NONE"

    materials = {name: material_for(name, m) for name, m in scene_file.get("materials", {}).items()}
    for index, shape in enumerate(scene_file.get("shapes", [])):
        if shape["type"] == "quad":
            corner, u, v = (to_blender(shape[k]) for k in ("corner", "edge_u", "edge_v"))
            points = [corner, *(tuple(c + d for c, d in zip(corner, e, strict=True)) for e in (u, v))]
            points.insert(2, tuple(a + b - c for a, b, c in zip(points[1], points[2], corner, strict=True)))
            mesh = bpy.data.meshes.new(f"quad{index}")
            mesh.from_pydata(points, [], [(0, 1, 2, 3)])  # normal u x v, lenspath's front face
            obj = bpy.data.objects.new(f"quad{index}", mesh)
            scene.collection.objects.link(obj)
        elif shape["type"] == "sphere":
            bpy.ops.mesh.primitive_uv_sphere_add(
                segments=128, ring_count=64, radius=float(shape["radius"]), location=to_blender(shape["center"])
            )
            obj = bpy.context.active_object
            bpy.ops.object.shade_smooth()
        else:
            sys.exit(f"shape {index}: type {shape['type']!r} is not rebuilt in Cycles by this script")
        if "emission" in shape:
            obj.data.materials.append(emitter(f"lamp{index}", shape["emission"]))
        else:
            obj.data.materials.append(materials[shape["material"]])

    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    background = world.node_tree.nodes["Background"]
    radiance = 0.0
    for light in scene_file.get("lights", []):
        if light["type"] != "environment":
            sys.exit(f"light type {light['type']!r} is not rebuilt in Cycles by this script")
        radiance = float(light["radiance"])
    background.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    background.inputs["Strength"].default_value = radiance
    scene.world = world

    view = scene_file["camera"]
    camera = bpy.data.cameras.new("camera")
    camera.sensor_fit = "VERTICAL"
    camera.angle_y = math.radians(float(view["fov_y_deg"]))
    camera.clip_start = 1e-3
    obj = bpy.data.objects.new("camera", camera)
    scene.collection.objects.link(obj)
    from mathutils import Vector

    eye, target = Vector(to_blender(view["eye"])), Vector(to_blender(view["look_at"]))
    obj.location = eye
    obj.rotation_euler = (target - eye).to_track_quat("-Z", "Y").to_euler()
    scene.camera = obj


def material_for(name: str, spec: dict):
    """A Cycles material for a scene file's material."""
    import bpy

    material = bpy.data.materials.new(name)
    material.use_nodes = True
    nodes = material.node_tree.nodes
    nodes.clear()
    output = nodes.new("ShaderNodeOutputMaterial")
    kind = spec["type"]
    if kind == "diffuse":
        bsdf = nodes.new("ShaderNodeBsdfDiffuse")
        bsdf.inputs["Color"].default_value = rgb(spec["reflectance"])
        bsdf.inputs["Roughness"].default_value = 0.0
    elif kind == "dielectric":
        bsdf = nodes.new("ShaderNodeBsdfGlass")
        bsdf.distribution = "GGX"
        bsdf.inputs["Roughness"].default_value = 0.0  # smooth: Cycles takes it as a delta lobe
        bsdf.inputs["IOR"].default_value = float(spec["eta"])
        bsdf.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    elif kind == "conductor":
        eta, k = METALS[spec["metal"]] if "metal" in spec else (spec["eta"], spec["k"])
        bsdf = nodes.new("ShaderNodeBsdfMetallic")
        bsdf.distribution = "GGX"
        bsdf.fresnel_type = "PHYSICAL_CONDUCTOR"
        bsdf.inputs["IOR"].default_value = tuple(float(x) for x in eta)
        bsdf.inputs["Extinction"].default_value = tuple(float(x) for x in k)
        bsdf.inputs["Roughness"].default_value = math.sqrt(float(spec.get("alpha", 0.0)))
    else:
        sys.exit(f"material {name}: type {kind!r} is not rebuilt in Cycles by this script")
    material.node_tree.links.new(bsdf.outputs[0], output.inputs["Surface"])
    return material


def emitter(name: str, radiance):
    """An emissive quad's material: `radiance` from its front face, black behind, as lenspath's."""
    import bpy

    material = bpy.data.materials.new(name)
    material.use_nodes = True
    nodes, links = material.node_tree.nodes, material.node_tree.links
    nodes.clear()
    output = nodes.new("ShaderNodeOutputMaterial")
    emission = nodes.new("ShaderNodeEmission")
    emission.inputs["Color"].default_value = rgb(radiance)
    emission.inputs["Strength"].default_value = 1.0
    black = nodes.new("ShaderNodeBsdfDiffuse")
    black.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    facing = nodes.new("ShaderNodeNewGeometry")
    mix = nodes.new("ShaderNodeMixShader")
    links.new(facing.outputs["Backfacing"], mix.inputs["Fac"])
    links.new(emission.outputs[0], mix.inputs[1])
    links.new(black.outputs[0], mix.inputs[2])
    links.new(mix.outputs[0], output.inputs["Surface"])
    material.cycles.emission_sampling = "FRONT"
    return material


def render_cycles(spp: int, seed: int, out: Path, guided: bool = True) -> float:
    """Renders the built scene at `spp` to `out`, with path guiding or without; returns the
    render's wall time in seconds."""
    import bpy

    scene = bpy.context.scene
    scene.cycles.use_guiding = guided
    scene.cycles.samples = spp
    scene.cycles.seed = seed
    scene.render.filepath = str(out)
    started = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    return time.perf_counter() - started


def render_lenspath(scene: str, res: tuple[int, int], integrator: str, spp: int, seed: int, out: Path) -> float:
    """Renders through the pinhole with `integrator`; returns lenspath's own render time."""
    command = [str(LENSPATH), "render", scene, "--camera", "pinhole", "--res", f"{res[0]}x{res[1]}"]
    command += ["--integrator", integrator, "--spp", str(spp), "--seed", str(seed), "--out", str(out)]
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode:
        sys.exit(f"{' '.join(command)}: {done.stderr.strip()}")
    return float(re.search(r"rendered .* in ([0-9.]+) s", done.stderr + done.stdout).group(1))


def sweep(render, reference, longest_s: float, folder: Path) -> list[tuple[int, float, float]]:
    """(spp, seconds, MSE) at 1, 2, 4, ... spp until a render takes longer than `longest_s`."""
    import numpy as np

    def measure(spp: int) -> tuple[float, float]:
        out = folder / f"sweep{spp}.exr"
        seconds = render(spp, spp + 11, out)
        return seconds, float(np.mean((read_exr(out) - reference) ** 2))

    return doubling_sweep(measure, longest_s)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="scenes/glass-and-gold.toml")
    parser.add_argument("--res", type=int, nargs=2, default=(320, 240), metavar=("W", "H"))
    parser.add_argument("--budgets", type=float, nargs="+", default=[2.0, 8.0])
    parser.add_argument("--ref-spp", type=int, default=2048)
    parser.add_argument("--json", type=Path, help="also write the curves and ratios here")
    args = parser.parse_args()
    in_venv(["numpy", "bpy", "OpenEXR"])
    import numpy as np

    subprocess.run(["cargo", "build", "--profile", "dist", "--locked", "-p", "lenspath-cli"], cwd=ROOT, check=True)
    scene_path = (ROOT / args.scene) if not Path(args.scene).is_absolute() else Path(args.scene)
    scene_file = tomllib.loads(scene_path.read_text())
    max_depth = int(scene_file.get("integrator", {}).get("max_depth", 16))
    res = tuple(args.res)
    build_cycles(scene_file, res, max_depth)
    name = scene_path.stem
    print(f"{name}, {res[0]}x{res[1]}, max depth {max_depth}, pinhole, both cores")
    renderers = {
        "lenspath path": lambda spp, seed, out: render_lenspath(str(scene_path), res, "path", spp, seed, out),
        "lenspath guided": lambda spp, seed, out: render_lenspath(str(scene_path), res, "guided", spp, seed, out),
        "Cycles guided": render_cycles,
        "Cycles path": lambda spp, seed, out: render_cycles(spp, seed, out, guided=False),
    }
    # Each renderer's converged image, by its path tracer (lenspath) or its guided render (Cycles):
    # each renderer's integrators converge to the same image.
    converged_by = {"lenspath": "lenspath path", "cycles": "Cycles guided"}
    CACHE.mkdir(parents=True, exist_ok=True)
    references, curves = {}, {}
    with tempfile.TemporaryDirectory() as temporary:
        folder = Path(temporary)
        render_cycles(4, 1, folder / "warm-up.exr")  # loads Cycles' kernels, untimed
        for owner, label in converged_by.items():
            cached = CACHE / f"guiding-{name}-{res[0]}x{res[1]}-{args.ref_spp}spp-{owner}.exr"
            if not cached.exists():
                seconds = renderers[label](args.ref_spp, 1_000_003, cached)
                print(f"  {owner} reference: {args.ref_spp} spp in {seconds:.0f} s", flush=True)
            references[owner] = read_exr(cached)
        for label, render in renderers.items():
            print(f"  {label}", flush=True)
            reference = references["cycles" if label.startswith("Cycles") else "lenspath"]
            curves[label] = sweep(render, reference, max(args.budgets), folder)
    means = {owner: float(image.mean()) for owner, image in references.items()}
    print(f"  mean of the references: lenspath {means['lenspath']:.4f}, Cycles {means['cycles']:.4f}")
    ratios = {}
    print("  budget   MSE / Cycles guided's: lenspath path, lenspath guided, Cycles without guiding")
    for budget in args.budgets:
        theirs = at_time(curves["Cycles guided"], budget)
        others = [at_time(curves[k], budget) for k in ("lenspath path", "lenspath guided", "Cycles path")]
        if theirs is None or None in others:
            print(f"  {budget:6.1f} s  (outside a curve)")
            continue
        ratios[budget] = dict(zip(("path", "guided", "cycles_path"), (o / theirs for o in others), strict=True))
        print(f"  {budget:6.1f} s  " + "  ".join(f"{r:6.3f}" for r in ratios[budget].values()))
    if args.json:
        args.json.write_text(json.dumps({"scene": name, "curves": curves, "ratios": ratios, "means": means}))
    return 0 if np.isfinite(list(means.values())).all() else 1


if __name__ == "__main__":
    sys.exit(main())
