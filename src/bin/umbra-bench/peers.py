#!/usr/bin/env python3
"""umbra against its peers, measured in the same run on the same machine (issue 25).

`rays`: umbra's ray throughput against Embree's on exactly the same rays. `umbra-bench rays
--dump DIR` writes each scene's triangles, its primary, shadow and diffuse rays and umbra's
answers; this runs it (umbra per core: LP_NUM_THREADS=1), traces the same rays with Embree 4
through `embreex` (its single-ray API, one thread), checks that both found the same hits, and
writes the ratios to peers.json with a Markdown table.

`path`: the path tracer against Mitsuba 3's `path` integrator (llvm_ad_rgb) on the same glTF
scene, camera, size, bounces and box filter: each renderer's relative MSE against its own
converged reference at several sample counts, and its time per sample (umbra: GPU timestamps;
Mitsuba: a warmed-up render), give the time each needs for equal error. Writes path.json.

Both print their table with `umbra-bench peers --table FILE` (also `peers.py table FILE`), the one
printer of these tables, which tests/bench.rs checks against BENCHMARKS.md without Python.

    pip install embreex mitsuba numpy pillow   # Mitsuba's llvm variant also needs apt's libllvm19; pillow decodes textures
    python3 src/bin/umbra-bench/peers.py rays --bench target/release/umbra-bench \
        --gltf ../shared/assets/gltf/SponzaDabrovic/sponza_dabrovic.glb --size 512x512
    python3 src/bin/umbra-bench/peers.py path --umbra target/release/umbra scenes/cornell-box.glb

Not run in CI. Ratios are what count: absolute per-core figures move 2x between machines.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np


def slug(name):
    """The file-name stem umbra-bench gives a scene (rays.rs `slug`)."""
    return "".join(c.lower() if c.isascii() and c.isalnum() else "-" for c in name)


def embree_scene(triangles):
    from embreex import rtcore_scene
    from embreex.mesh_construction import TriangleMesh

    scene = rtcore_scene.EmbreeScene()
    TriangleMesh(scene, triangles)
    return scene


def trace(scene, rays, kind):
    """Embree's answers: the triangle hit (or -1) per ray; any hit: 1 occluded, 0 clear."""
    origins, dirs = np.ascontiguousarray(rays[:, 0:3]), np.ascontiguousarray(rays[:, 4:7])
    tmax = np.ascontiguousarray(np.minimum(rays[:, 7], np.float32(1e30)))
    if kind == "shadow":
        # embreex's OCCLUDED answers the geometry that blocks (0 here) or -1 for a clear ray.
        return (scene.run(origins, dirs, dists=tmax, query="OCCLUDED") >= 0).astype(np.int64)
    return scene.run(origins, dirs, dists=tmax).astype(np.int64)


def rays(args):
    if not args.gltf:
        assets = os.environ.get("UMBRA_ASSETS")
        if not assets:
            sys.exit("peers.py rays: name the scenes with --gltf, or set UMBRA_ASSETS (Sponza is taken from it)")
        args.gltf = [str(Path(assets) / "gltf/SponzaDabrovic/sponza_dabrovic.glb")]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    env = dict(os.environ, LP_NUM_THREADS=args.threads)
    command = [args.bench, "rays", "--no-terrain", "--size", args.size, "--repeats", str(args.repeats),
               "--dump", str(out / "dump"), "--out", str(out)]
    for g in args.gltf:
        command += ["--gltf", g]
    print("running", " ".join(command), f"(LP_NUM_THREADS={args.threads})", flush=True)
    subprocess.run(command, env=env, check=True)
    umbra = json.loads((out / "rays.json").read_text())

    import embreex

    results = []
    for scene in umbra["scenes"]:
        stem = out / "dump" / slug(scene["scene"])
        triangles = np.fromfile(f"{stem}-triangles.f32", dtype="<f4").reshape(-1, 3, 3)
        started = time.perf_counter()
        embree = embree_scene(triangles)
        build_ms = (time.perf_counter() - started) * 1e3
        row = {"scene": scene["scene"], "triangles": len(triangles), "embree_build_ms": build_ms,
               "umbra_build_ms": scene["binned_build_ms_median"], "kinds": []}
        for kind in scene["rays"]:
            name = kind["kind"]
            rays = np.fromfile(f"{stem}-{name}.f32", dtype="<f4").reshape(-1, 8)
            answers = np.fromfile(f"{stem}-{name}.u32", dtype="<u4").astype(np.int64)
            if name != "shadow":
                answers[answers == 0xFFFFFFFF] = -1
            trace(embree, rays, name)  # warm-up
            times = []
            for _ in range(args.repeats):
                started = time.perf_counter()
                hits = trace(embree, rays, name)
                times.append(time.perf_counter() - started)
            seconds = statistics.median(times)
            embree_mrays = len(rays) / seconds / 1e6
            agree = float(np.mean(hits == answers))
            row["kinds"].append({
                "kind": name, "rays": len(rays),
                "umbra_mrays_per_s": kind["mrays_per_s"], "embree_mrays_per_s": embree_mrays,
                "ratio": kind["mrays_per_s"] / embree_mrays, "same_answer": agree,
            })
            print(f"{scene['scene']}: {name:8} umbra {kind['mrays_per_s']:.2f} Mrays/s, "
                  f"Embree {embree_mrays:.2f} Mrays/s, ratio {kind['mrays_per_s'] / embree_mrays:.2f}, "
                  f"same answer {100 * agree:.2f} %", flush=True)
        results.append(row)

    doc = {"device": umbra["device"], "umbra_threads": args.threads, "embree": "embreex " + getattr(embreex, "__version__", "?"),
           "embree_threads": 1, "size": umbra["size"], "repeats": args.repeats, "scenes": results}
    (out / "peers.json").write_text(json.dumps(doc, indent=2))
    print(f"wrote {out / 'peers.json'}")
    print_table(args.bench, out / "peers.json")


def print_table(bench, path):
    """Prints the Markdown table of a peers.json or path.json. `umbra-bench peers --table` is the
    one printer of both (BENCHMARKS.md carries its output, and tests/bench.rs, which runs without
    Python, checks it)."""
    subprocess.run([bench, "peers", "--table", str(path)], check=True)


def read_glb(path):
    """The JSON and BIN chunk of a .glb file."""
    import struct
    data = Path(path).read_bytes()
    json_len = struct.unpack_from("<I", data, 12)[0]
    doc = json.loads(data[20:20 + json_len])
    rest = 20 + json_len
    bin_len = struct.unpack_from("<I", data, rest)[0]
    return doc, data[rest + 8:rest + 8 + bin_len]


def accessor(doc, blob, index):
    """An accessor's elements as a numpy array (float32 VEC3 or unsigned SCALAR indices)."""
    a = doc["accessors"][index]
    view = doc["bufferViews"][a["bufferView"]]
    dtype = {5126: "<f4", 5125: "<u4", 5123: "<u2", 5121: "u1"}[a["componentType"]]
    width = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}[a["type"]]
    start = view.get("byteOffset", 0) + a.get("byteOffset", 0)
    values = np.frombuffer(blob, dtype=dtype, count=a["count"] * width, offset=start)
    return values.reshape(-1, width) if width > 1 else values


def node_matrix(node):
    """A glTF node's local transform, 4×4 (column vectors)."""
    if "matrix" in node:
        return np.array(node["matrix"], dtype=np.float64).reshape(4, 4).T
    x, y, z, w = node.get("rotation", [0, 0, 0, 1])
    r = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                  [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                  [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    m = np.eye(4)
    m[:3, :3] = r * np.array(node.get("scale", [1, 1, 1]))
    m[:3, 3] = node.get("translation", [0, 0, 0])
    return m


def srgb_to_linear(c):
    """The sRGB transfer function's inverse, per element."""
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def glb_image(doc, blob, texture):
    """Texture `texture`'s image, decoded to floats in [0, 1] (height × width × 4)."""
    import io
    from PIL import Image
    image = doc["images"][doc["textures"][texture]["source"]]
    view = doc["bufferViews"][image["bufferView"]]
    start = view.get("byteOffset", 0)
    data = Image.open(io.BytesIO(blob[start:start + view["byteLength"]])).convert("RGBA")
    return np.asarray(data, dtype=np.float32) / 255.0


def world_primitives(doc, blob):
    """Every mesh primitive of the default scene: (node index, primitive index, primitive, world)."""
    out = []

    def walk(index, parent):
        node = doc["nodes"][index]
        world = parent @ node_matrix(node)
        for p, prim in enumerate(doc["meshes"][node["mesh"]]["primitives"] if "mesh" in node else []):
            out.append((index, p, prim, world))
        for child in node.get("children", []):
            walk(child, world)

    for root in doc["scenes"][doc.get("scene", 0)]["nodes"]:
        walk(root, np.eye(4))
    return out


def with_camera(path, work):
    """`path`, or when it has no camera a copy in `work` with one framing the scene from +Z
    (a vertical field of 45°, the bounds' sphere filling 90 % of it), for both renderers."""
    import struct
    doc, blob = read_glb(path)
    if doc.get("cameras"):
        return str(path)
    points = []
    for _, _, prim, world in world_primitives(doc, blob):
        positions = accessor(doc, blob, prim["attributes"]["POSITION"]).astype(np.float64)
        points.append((np.c_[positions, np.ones(len(positions))] @ world.T)[:, :3])
    points = np.concatenate(points)
    lo, hi = points.min(axis=0), points.max(axis=0)
    centre, radius = (lo + hi) / 2, np.linalg.norm(hi - lo) / 2
    yfov = np.radians(45.0)
    distance = radius / np.sin(0.9 * yfov / 2)
    doc["cameras"] = [{"type": "perspective", "perspective": {"yfov": yfov, "znear": 0.01}}]
    doc["nodes"].append({"camera": 0, "translation": (centre + [0, 0, distance]).tolist()})
    doc["scenes"][doc.get("scene", 0)]["nodes"].append(len(doc["nodes"]) - 1)
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    padded = blob + b"\0" * (-len(blob) % 4)
    out = Path(work) / (Path(path).stem + "-camera.glb")
    out.write_bytes(struct.pack("<III", 0x46546C67, 2, 12 + 8 + len(text) + 8 + len(padded))
                    + struct.pack("<II", len(text), 0x4E4F534A) + text
                    + struct.pack("<II", len(padded), 0x004E4942) + padded)
    return str(out)


def mitsuba_scene(path, size, max_depth, rr_depth, work, env=None, sampler="independent"):
    """The glTF scene as a Mitsuba 3 scene with Mitsuba's own plugins (the peer's speed, not a
    literal copy of the glTF BRDF): meshes in world space (with normals and UVs where the
    material has textures), metallic-roughness as `diffuse` (metallic 0, roughness 1: the glTF
    BRDF's diffuse lobe; its 4 % specular at roughness 1 is left out) or `principled` otherwise,
    base colour, metallic-roughness (B, G), emissive and normal textures as bitmaps (decoded to
    linear here), emission as an area emitter, the first camera, a box filter; `env` =
    (equirectangular map, strength) as Mitsuba's `envmap` turned by half a turn about +Y, so that
    directions meet the texels umbra gives them (Mitsuba's u is umbra's − 1/2, as
    tests/reference/mitsuba_refs.py found); `sampler` Mitsuba's sampler plugin. Meshes,
    materials, cameras and TRS/matrix nodes only."""
    import mitsuba as mi
    doc, blob = read_glb(path)
    scene = {"type": "scene", "integrator": {"type": "path", "max_depth": max_depth, "rr_depth": rr_depth}}
    camera = None

    def bitmap(texture, channels, linear_from_srgb, scale=1.0):
        image = glb_image(doc, blob, texture)[:, :, channels]
        if linear_from_srgb:
            image = srgb_to_linear(image)
        return {"type": "bitmap", "raw": True, "bitmap": mi.Bitmap(np.ascontiguousarray(image * scale))}

    def walk(index, parent):
        nonlocal camera
        node = doc["nodes"][index]
        world = parent @ node_matrix(node)
        if "camera" in node and camera is None:
            camera = (world, doc["cameras"][node["camera"]])
        for child in node.get("children", []):
            walk(child, world)

    for root in doc["scenes"][doc.get("scene", 0)]["nodes"]:
        walk(root, np.eye(4))
    for index, p, prim, world in world_primitives(doc, blob):
        m = doc["materials"][prim.get("material", 0)] if "materials" in doc else {}
        pbr = m.get("pbrMetallicRoughness", {})
        textured = any(k in m for k in ["normalTexture", "emissiveTexture"]) or any(
            k in pbr for k in ["baseColorTexture", "metallicRoughnessTexture"])
        positions = accessor(doc, blob, prim["attributes"]["POSITION"]).astype(np.float64)
        positions = (np.c_[positions, np.ones(len(positions))] @ world.T)[:, :3]
        faces = accessor(doc, blob, prim["indices"]).astype(np.uint32).reshape(-1, 3)
        if np.linalg.det(world[:3, :3]) < 0:
            faces = faces[:, ::-1]
        mesh = mi.Mesh(f"node{index}-{p}", len(positions), len(faces), has_vertex_normals=textured,
                       has_vertex_texcoords=textured)
        params = mi.traverse(mesh)
        params["vertex_positions"] = mi.Float(positions.astype(np.float32).ravel())
        params["faces"] = mi.UInt32(np.ascontiguousarray(faces).ravel())
        if textured:
            normals = accessor(doc, blob, prim["attributes"]["NORMAL"]).astype(np.float64)
            normals = normals @ np.linalg.inv(world[:3, :3])
            normals /= np.linalg.norm(normals, axis=1, keepdims=True)
            params["vertex_normals"] = mi.Float(normals.astype(np.float32).ravel())
            params["vertex_texcoords"] = mi.Float(accessor(doc, blob, prim["attributes"]["TEXCOORD_0"]).astype(np.float32).ravel())
        params.update()
        base = pbr.get("baseColorFactor", [1, 1, 1, 1])[:3]
        metallic, roughness = pbr.get("metallicFactor", 1.0), pbr.get("roughnessFactor", 1.0)
        if metallic == 0 and roughness == 1 and not textured:
            bsdf = {"type": "diffuse", "reflectance": {"type": "rgb", "value": base}}
        else:
            bsdf = {"type": "principled", "base_color": {"type": "rgb", "value": base},
                    "metallic": metallic, "roughness": roughness}
            if "baseColorTexture" in pbr:
                bsdf["base_color"] = bitmap(pbr["baseColorTexture"]["index"], [0, 1, 2], True, np.array(base, np.float32))
            if "metallicRoughnessTexture" in pbr:
                bsdf["metallic"] = bitmap(pbr["metallicRoughnessTexture"]["index"], [2], False, metallic)
                bsdf["roughness"] = bitmap(pbr["metallicRoughnessTexture"]["index"], [1], False, roughness)
            if "normalTexture" in m:
                bsdf = {"type": "normalmap", "normalmap": bitmap(m["normalTexture"]["index"], [0, 1, 2], False), "bsdf": bsdf}
        # In a PLY beside the output: Mitsuba attaches a BSDF and an emitter to a shape it
        # loads, not to a mesh built in memory.
        ply = Path(work) / f"node{index}-{p}.ply"
        mesh.write_ply(str(ply))
        shape = {"type": "ply", "filename": str(ply), "face_normals": not textured, "bsdf": bsdf}
        strength = m.get("extensions", {}).get("KHR_materials_emissive_strength", {}).get("emissiveStrength", 1.0)
        emissive = [strength * e for e in m.get("emissiveFactor", [0, 0, 0])]
        if any(emissive):
            radiance = {"type": "rgb", "value": emissive}
            if "emissiveTexture" in m:
                radiance = bitmap(m["emissiveTexture"]["index"], [0, 1, 2], True, np.array(emissive, np.float32))
            shape["emitter"] = {"type": "area", "radiance": radiance}
        scene[f"node{index}-{p}"] = shape
    if camera is None:
        raise SystemExit(f"{path}: the scene has no camera")
    if env is not None:
        scene["environment"] = {"type": "envmap", "filename": str(env[0]), "scale": env[1],
                                "to_world": mi.ScalarTransform4f().rotate([0, 1, 0], 180)}
    world, cam = camera
    origin = world[:3, 3]
    forward = -world[:3, 2] / np.linalg.norm(world[:3, 2])
    up = world[:3, 1] / np.linalg.norm(world[:3, 1])
    scene["sensor"] = {
        "type": "perspective", "fov_axis": "y", "fov": float(np.degrees(cam["perspective"]["yfov"])),
        "to_world": mi.ScalarTransform4f().look_at(origin=origin.tolist(), target=(origin + forward).tolist(), up=up.tolist()),
        "film": {"type": "hdrfilm", "width": size[0], "height": size[1], "rfilter": {"type": "box"}, "pixel_format": "rgb"},
        "sampler": {"type": sampler},
    }
    return mi.load_dict(scene)


def relative_mse(image, reference):
    """Mean over pixels and channels of (x - ref)^2 / (ref^2 + 0.01) (umbra-bench's metric)."""
    return float(np.mean((image - reference) ** 2 / (reference ** 2 + 0.01)))


def umbra_render(args, spp, seed, out):
    """umbra's path-traced image (rgb) and GPU milliseconds for `spp` samples per pixel."""
    import mitsuba as mi
    exr = out / f"umbra-{spp}-{seed}.exr"
    command = [args.umbra, "render", args.scene, "--size", args.size, "--spp", str(spp), "--seed", str(seed),
               "--max-bounces", str(args.max_bounces), "--rr-depth", str(args.rr_depth),
               "--exr", str(exr), "-o", str(exr.with_suffix(".png"))]
    if args.env:
        command += ["--env", args.env, "--env-strength", str(args.env_strength)]
    run = subprocess.run(command, check=True, capture_output=True, text=True)
    line = next(l for l in run.stdout.splitlines() + run.stderr.splitlines() if l.startswith("pathtrace:"))
    gpu_ms = float(line.split("(GPU ")[1].split(" ms")[0])
    image = np.array(mi.Bitmap(str(exr)), dtype=np.float64)[:, :, :3]
    return image, gpu_ms


def mitsuba_render(scene, spp, seed):
    """Mitsuba's image and wall milliseconds for `spp` samples per pixel (after a warm-up render
    of the same size, so its kernels are compiled and cached)."""
    import drjit as dr
    import mitsuba as mi
    image = mi.render(scene, spp=spp, seed=seed + 1000)
    dr.eval(image)
    dr.sync_thread()
    started = time.perf_counter()
    image = mi.render(scene, spp=spp, seed=seed)
    dr.eval(image)
    dr.sync_thread()
    return np.array(image, dtype=np.float64), (time.perf_counter() - started) * 1e3


def path(args):
    import mitsuba as mi
    mi.set_variant("llvm_ad_rgb")
    import drjit as dr
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    size = tuple(int(v) for v in args.size.lower().split("x"))
    spps = [int(v) for v in args.spp.split(",")]
    args.scene = with_camera(args.scene, out)
    env = (args.env, args.env_strength) if args.env else None
    scene = mitsuba_scene(args.scene, size, args.max_bounces + 1, args.rr_depth + 1, out, env, args.mitsuba_sampler)
    print(f"references: {args.reference_spp} spp each", flush=True)
    references = {"umbra": umbra_render(args, args.reference_spp, 99, out)[0],
                  "mitsuba": mitsuba_render(scene, args.reference_spp, 99)[0]}
    between = relative_mse(references["umbra"], references["mitsuba"])
    print(f"umbra's and Mitsuba's references differ by relative MSE {between:.2e}", flush=True)
    rows = []
    for spp in spps:
        row = {"spp": spp}
        for name in ["umbra", "mitsuba"]:
            image, ms = umbra_render(args, spp, 1, out) if name == "umbra" else mitsuba_render(scene, spp, 1)
            error = relative_mse(image, references[name])
            # Equal-error time: time per sample x samples to reach relative MSE 1e-3 (variance ~ 1/spp).
            row[name] = {"ms": ms, "rel_mse": error, "ms_at_1e-3": ms / spp * (error * spp / 1e-3)}
        row["ratio"] = row["umbra"]["ms_at_1e-3"] / row["mitsuba"]["ms_at_1e-3"]
        print(f"{spp:5} spp: umbra {row['umbra']['ms']:8.1f} ms rel MSE {row['umbra']['rel_mse']:.2e}; "
              f"Mitsuba {row['mitsuba']['ms']:8.1f} ms rel MSE {row['mitsuba']['rel_mse']:.2e}; "
              f"umbra needs {row['ratio']:.2f}x Mitsuba's time for equal error", flush=True)
        rows.append(row)
    doc = {"scene": args.scene, "env": args.env, "size": size, "max_bounces": args.max_bounces, "rr_depth": args.rr_depth,
           "reference_spp": args.reference_spp, "references_rel_mse": between, "mitsuba_sampler": args.mitsuba_sampler,
           "renderers": {"umbra": "umbra render (GPU timestamps)", "mitsuba": f"Mitsuba {mi.__version__} llvm_ad_rgb path, {args.mitsuba_sampler} sampler, {dr.thread_count()} threads (wall)"},
           "rows": rows}
    (out / "path.json").write_text(json.dumps(doc, indent=2))
    print(f"wrote {out / 'path.json'}")
    print_table(args.bench, out / "path.json")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    r = commands.add_parser("rays", help="ray throughput against Embree")
    r.add_argument("--bench", default="target/release/umbra-bench", help="the umbra-bench binary")
    r.add_argument("--gltf", action="append", default=[], help="glTF scenes (repeatable)")
    r.add_argument("--size", default="512x512", help="rays per kind as a WxH primary image")
    r.add_argument("--repeats", type=int, default=5, help="timed repeats (median)")
    r.add_argument("--threads", default="1", help="LP_NUM_THREADS for umbra (lavapipe): per core")
    r.add_argument("--out", default="out/bench/peers", help="where to write peers.json")
    p = commands.add_parser("path", help="path tracing at equal error against Mitsuba 3")
    p.add_argument("scene", nargs="?", default="scenes/cornell-box.glb", help="a .glb file")
    p.add_argument("--umbra", default="target/release/umbra", help="the umbra binary")
    p.add_argument("--bench", default="target/release/umbra-bench", help="the umbra-bench binary (prints the table)")
    p.add_argument("--size", default="128x128", help="image size WxH")
    p.add_argument("--spp", default="16,64,256", help="sample counts compared")
    p.add_argument("--reference-spp", type=int, default=4096, help="each renderer's reference")
    p.add_argument("--max-bounces", type=int, default=8, help="umbra's --max-bounces (Mitsuba max_depth = this + 1)")
    p.add_argument("--rr-depth", type=int, default=5, help="Russian roulette from this many bounces, both")
    p.add_argument("--env", help="an equirectangular environment map (EXR) lighting the scene in both")
    p.add_argument("--env-strength", type=float, default=1.0, help="its multiplier")
    p.add_argument("--mitsuba-sampler", default="independent",
                   help="Mitsuba's sampler: independent (its default) or a stratified one (ldsampler, multijitter, ...)")
    p.add_argument("--out", default="out/bench/peers", help="where to write path.json")
    t = commands.add_parser("table", help="print the Markdown table of a peers.json or path.json (umbra-bench peers --table)")
    t.add_argument("json")
    t.add_argument("--bench", default="target/release/umbra-bench", help="the umbra-bench binary")
    args = parser.parse_args()
    if args.command == "rays":
        rays(args)
    elif args.command == "path":
        path(args)
    else:
        print_table(args.bench, args.json)


if __name__ == "__main__":
    main()
