#!/usr/bin/env python3
"""Makes docs/montage.jpg, the picture README.md opens with: umbra's own renders from the
Khronos gallery (docs/khronos/*.png, made by scripts/khronos-gallery.py), in two rows of equal
height about 1600 px wide.

Each gallery image is umbra's path-traced render (left) beside the Khronos Sample Viewer's
screenshot (right), split by a white gap; the montage keeps the left part only, so every tile is
umbra's. The charts in docs/bench/*.png are plots, not renders, and are left out.

Needs Pillow. Where `python3 -c "import PIL"` fails (as on the machine it was first run on),
install it into a virtual environment under /tmp and run the script with that interpreter:

    python3 -m venv /tmp/montage-venv && /tmp/montage-venv/bin/pip install pillow
    /tmp/montage-venv/bin/python docs/montage.py            # from the repository's root

Options: --width (default 1600), --gap (default 6), --out (default docs/montage.jpg;
a JPEG at quality 90, a fifth of the PNG's size for the same view).
"""
import argparse
import os

from PIL import Image

HERE = os.path.dirname(os.path.abspath(__file__))

# The rows, left to right: each row's images are scaled to one height so that the row fills the
# width. AnisotropyRotationTest's ten objects are small in its framing, but it is the widest tile
# and balances the second row's tall lamps.
ROWS = [
    ["ToyCar", "TransmissionTest", "SheenChair"],
    ["ClearcoatWicker", "AnisotropyBarnLamp", "IridescenceLamp", "AnisotropyRotationTest"],
]


def umbra_half(path):
    """The gallery image's left part: the columns before the first all-white column (the gap
    between umbra's render and the Sample Viewer's screenshot)."""
    image = Image.open(path).convert("RGB")
    width, height = image.size
    pixels = image.load()
    for x in range(width // 4, width):
        if all(min(pixels[x, y]) > 245 for y in range(0, height, 2)):
            return image.crop((0, 0, x, height))
    raise SystemExit(f"{path}: no white gap between the two renders")


def row_image(images, width, gap):
    """One row of the montage: the images scaled to the height at which they and the gaps
    between them fill `width`."""
    aspect = sum(i.width / i.height for i in images)
    height = round((width - gap * (len(images) - 1)) / aspect)
    scaled = [i.resize((max(1, round(i.width * height / i.height)), height), Image.LANCZOS) for i in images]
    # Rounding leaves the row a pixel or two off: the last tile takes up the difference.
    used = sum(s.width for s in scaled[:-1]) + gap * (len(scaled) - 1)
    scaled[-1] = scaled[-1].resize((width - used, height), Image.LANCZOS)
    row = Image.new("RGB", (width, height), "white")
    x = 0
    for s in scaled:
        row.paste(s, (x, 0))
        x += s.width + gap
    return row


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--width", type=int, default=1600)
    parser.add_argument("--gap", type=int, default=6)
    parser.add_argument("--out", default=os.path.join(HERE, "montage.jpg"))
    args = parser.parse_args()
    rows = [
        row_image([umbra_half(os.path.join(HERE, "khronos", f"{name}.png")) for name in names], args.width, args.gap)
        for names in ROWS
    ]
    height = sum(r.height for r in rows) + args.gap * (len(rows) - 1)
    montage = Image.new("RGB", (args.width, height), "white")
    y = 0
    for r in rows:
        montage.paste(r, (0, y))
        y += r.height + args.gap
    if args.out.lower().endswith((".jpg", ".jpeg")):
        montage.convert("RGB").save(args.out, quality=90, optimize=True)
    else:
        montage.save(args.out, optimize=True)
    print(f"{args.out}: {montage.width}×{montage.height}")


if __name__ == "__main__":
    main()
