"""Prepares the raw RGBA inputs of make.mjs (the three PNGs of scenes/textured.glb and a 37x23
gradient with alpha), and turns its transcoded outputs into the reference PNGs:

    python3 prepare.py inputs /tmp/k            # writes /tmp/k/*.rgba and sizes.json
    node make.mjs /tmp/k tests/scene/ktx2       # encodes *.ktx2, transcodes *.rgba (Binomial's C++)
    python3 prepare.py references /tmp/k tests/scene/ktx2
"""
import io, json, struct, sys
from pathlib import Path
from PIL import Image

JOBS = {
    "checker-etc1s-srgb-mips": "checker",
    "bumps-uastc-zstd-mips": "bumps",
    "metal-rough-uastc": "metal-rough",
    "gradient-etc1s-alpha": "gradient",
    "gradient-uastc-zstd-alpha": "gradient",
}

def inputs(out):
    glb = (Path(__file__).parents[3] / "scenes/textured.glb").read_bytes()
    length = struct.unpack("<I", glb[12:16])[0]
    root, binary = json.loads(glb[20 : 20 + length]), glb[20 + length + 8 :]
    sizes = {}
    for image in root["images"]:
        view = root["bufferViews"][image["bufferView"]]
        start = view.get("byteOffset", 0)
        img = Image.open(io.BytesIO(binary[start : start + view["byteLength"]])).convert("RGBA")
        (out / f"{image['name']}.rgba").write_bytes(img.tobytes())
        sizes[image["name"]] = img.size
    # Smooth ramps, a hard-edged blue checker and an alpha ramp; 37x23 is no multiple of 4x4 blocks.
    w, h = 37, 23
    px = bytearray()
    for y in range(h):
        for x in range(w):
            blue = 255 if (x // 5 + y // 5) % 2 else 40
            px += bytes([int(255 * x / (w - 1)), int(255 * y / (h - 1)), blue, int(255 * ((x + y) / (w + h - 2)))])
    (out / "gradient.rgba").write_bytes(px)
    sizes["gradient"] = (w, h)
    (out / "sizes.json").write_text(json.dumps(sizes))

def references(raw, out):
    sizes = json.loads((raw / "sizes.json").read_text())
    for name, image in JOBS.items():
        pixels = (out / f"{name}.rgba").read_bytes()
        Image.frombytes("RGBA", tuple(sizes[image]), pixels).save(out / f"{name}.reference.png", optimize=True)
        (out / f"{name}.rgba").unlink()

if __name__ == "__main__":
    if sys.argv[1] == "inputs":
        inputs(Path(sys.argv[2]))
    else:
        references(Path(sys.argv[2]), Path(sys.argv[3]))
