#!/usr/bin/env python3
"""Renders the Khronos material test models beside the Sample Viewer's screenshots.

    cargo build --release && python3 scripts/khronos-gallery.py [--assets ../shared/assets] [--spp 64]

For each model in MODELS whose files exist under ASSETS/gltf, the release `umbra` binary path
traces it (its first camera, else one framing it; ASSETS/hdr/courtyard.exr; denoised; the Khronos
PBR Neutral tone curve, as the Sample Viewer's default) at the
screenshot's aspect, 384 px wide, and docs/khronos/<Model>.png gets the render (left) and the
screenshot scaled to the same height (right). docs/khronos.md lists every model: the image, the
extensions it uses (from its extensionsUsed), and the note below, written by looking at the
images (update it when a render changes). A model with files missing is listed with the missing
files; one umbra refuses, with umbra's error. Needs Python 3 with Pillow; not run in CI.
"""

import argparse
import json
import os
import struct
import subprocess
import sys
import tempfile

from PIL import Image

# (model, folder under gltf/, what differs from the Sample Viewer's screenshot)
MODELS = [
    ("ToyCar", "glTF",
     "The file's camera 0 sees the car closer and from higher than the viewer; paint, flame decals, chrome and "
     "the sheen cloth all read alike, but the courtyard's warm sun makes the paint brighter and puts the yard's "
     "sharp reflections in the clear coat where the viewer shows soft studio ones."),
    ("SheenChair", "glTF",
     "Fabric and wood agree in colour and the fabric reads velvety; umbra's framing camera shows the chair "
     "smaller, and against the sunlit courtyard the sheen's brightening along the cushions' rims is fainter than "
     "on the viewer's grey backdrop."),
    ("ClearcoatWicker", "glTF-Binary",
     "The woven wood and the coat's sharp highlight both show; the sphere is smaller (framing camera) and the "
     "coat mirrors the bright courtyard, so it looks glossier all over than in the viewer's dark studio."),
    ("AnisotropyBarnLamp", "glTF",
     "Without its base-colour texture the metal is the factor's pale pink instead of copper; the shade's "
     "highlight is stretched along the brushing as in the viewer, but narrower under the courtyard's sun, and "
     "the glass bulb is clear in both."),
    ("AnisotropyRotationTest", "glTF-Binary",
     "At 384 px the framing camera (the bounding sphere in a 45° view) leaves the ten objects too small to "
     "compare their highlights' directions; the viewer's crop shows each one's stretched highlight."),
    ("IridescenceLamp", "glTF",
     "The globe shows the film's green and magenta fringes in both; umbra's level view does not see the "
     "shade's silver inside (the viewer looks from lower), the sunlit shade is brown rather than near black, "
     "and the globe keeps some speckle of caustic paths through the glass that 64 spp and the denoiser leave."),
    ("IridescenceDielectricSpheres", "glTF", ""),
    ("TransmissionTest", "glTF-Binary",
     "The tints, the striped transmission textures and the opacity columns agree; umbra refracts the "
     "courtyard-lit checkerboard through each sphere with warmer colours, and its rough row is less frosted "
     "than the viewer's."),
    ("DragonAttenuation", "glTF", ""),
]
WIDTH = 384


def gltf_json(path):
    """The JSON of a .gltf or .glb file."""
    with open(path, "rb") as f:
        data = f.read()
    if path.endswith(".glb"):
        length = struct.unpack_from("<I", data, 12)[0]
        return json.loads(data[20 : 20 + length])
    return json.loads(data)


def missing_files(path, doc):
    """External buffers and images the file names that are not there."""
    folder = os.path.dirname(path)
    uris = [x.get("uri") for x in doc.get("buffers", []) + doc.get("images", [])]
    return [u for u in uris if u and not u.startswith("data:") and not os.path.exists(os.path.join(folder, u))]


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--assets", default=os.path.join(root, "..", "shared", "assets"))
    parser.add_argument("--umbra", default=os.path.join(root, "target", "release", "umbra"))
    parser.add_argument("--spp", type=int, default=64)
    parser.add_argument("--only", nargs="*", help="render only these models (none: only rewrite the table)")
    args = parser.parse_args()
    out_dir = os.path.join(root, "docs", "khronos")
    os.makedirs(out_dir, exist_ok=True)
    env = os.path.join(args.assets, "hdr", "courtyard.exr")
    rows = []
    for name, sub, note in MODELS:
        folder = os.path.join(args.assets, "gltf", name)
        files = [f for f in sorted(os.listdir(os.path.join(folder, sub))) if f.endswith((".gltf", ".glb"))]
        path = os.path.join(folder, sub, files[0])
        doc = gltf_json(path)
        extensions = ", ".join(e.removeprefix("KHR_materials_") for e in doc.get("extensionsUsed", []))
        shot = [f for f in os.listdir(folder) if f.startswith("screenshot.")][0]
        missing = missing_files(path, doc)
        buffers_missing = [u for u in missing if u.endswith(".bin")]
        if buffers_missing:
            rows.append((name, extensions, None, f"not rendered: {', '.join(buffers_missing)} missing from the shared assets"))
            continue
        image = f"khronos/{name}.png"
        if args.only is None or name in args.only:
            with Image.open(os.path.join(folder, shot)) as s:
                screenshot = s.convert("RGB")
            height = round(WIDTH * screenshot.height / screenshot.width) // 2 * 2
            with tempfile.TemporaryDirectory() as tmp:
                render = os.path.join(tmp, "render.png")
                cmd = [args.umbra, "render", path, "--env", env, "--spp", str(args.spp),
                       "--size", f"{WIDTH}x{height}", "--denoise", "--tonemap", "neutral", "--missing-textures", "warn",
                       "-o", render]
                print(" ".join(cmd), flush=True)
                run = subprocess.run(cmd, capture_output=True, text=True)
                if run.returncode != 0:
                    error = run.stderr.strip().splitlines()[-1] if run.stderr.strip() else f"exit {run.returncode}"
                    print(error, file=sys.stderr)
                    rows.append((name, extensions, None, f"umbra refuses it: {error}"))
                    continue
                with Image.open(render) as r:
                    left = r.convert("RGB")
            right = screenshot.resize((round(screenshot.width * height / screenshot.height), height), Image.LANCZOS)
            pair = Image.new("RGB", (left.width + 4 + right.width, height), (255, 255, 255))
            pair.paste(left, (0, 0))
            pair.paste(right, (left.width + 4, 0))
            out = os.path.join(out_dir, f"{name}.png")
            pair.save(out, optimize=True)
            if os.path.getsize(out) > 300_000:  # keep the repository small: 256 colours, dithered
                pair.quantize(256, dither=Image.Dither.FLOYDSTEINBERG).save(out, optimize=True)
        if missing:
            note = f"{', '.join(missing)} missing from the shared assets: rendered with `--missing-textures warn` (the factors alone). {note}"
        rows.append((name, extensions, image, note))
    with open(os.path.join(root, "docs", "khronos.md"), "w") as md:
        md.write("# Khronos material test models\n\n")
        md.write(f"Left: umbra's path tracer ({args.spp} spp, denoised, `courtyard.exr`, PBR Neutral tone curve, the model's first camera or one "
                 "framing it); right: the Khronos Sample Viewer's screenshot shipped with the model (its own camera and "
                 "lighting, so framing and light differ by design). Generated by `python3 scripts/khronos-gallery.py`.\n\n")
        md.write("| model | umbra (left) and the Sample Viewer | extensions | how umbra's render differs |\n|---|---|---|---|\n")
        for name, extensions, image, note in rows:
            cell = f"![{name}]({image})" if image else "—"
            md.write(f"| {name} | {cell} | {extensions} | {note} |\n")


if __name__ == "__main__":
    main()
