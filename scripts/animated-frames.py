#!/usr/bin/env python3
"""Makes docs/images/animated-frames.jpg: eight frames of scenes/animated.glb's 2-second loop
(frames 0..8 at 4 fps: a skin bending, a rigid roller turning, a ball squashed by a morph
target), path-traced by `umbra render --frames` (one load, the BVH refitted each frame) at
64 spp and denoised, in two rows of four. Needs Pillow and a release build:

    cargo build --release && python3 scripts/animated-frames.py     # from the repository's root
"""
import os
import subprocess
import tempfile

from PIL import Image

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

with tempfile.TemporaryDirectory() as tmp:
    subprocess.run(
        [os.path.join(ROOT, "target/release/umbra"), "render", os.path.join(ROOT, "scenes/animated.glb"),
         "--frames", "0..8", "--fps", "4", "--size", "256x192", "--spp", "64", "--denoise",
         "-o", os.path.join(tmp, "frame-%d.png")],
        check=True,
    )
    frames = [Image.open(os.path.join(tmp, f"frame-{i}.png")).convert("RGB") for i in range(8)]
    w, h = frames[0].size
    sheet = Image.new("RGB", (4 * w, 2 * h))
    for i, frame in enumerate(frames):
        sheet.paste(frame, ((i % 4) * w, (i // 4) * h))
    out = os.path.join(ROOT, "docs/images/animated-frames.jpg")
    sheet.save(out, quality=90)
    print("wrote", out)
