// Encodes the test images to KTX2 with Binomial's basisu encoder (ktx2-encoder's WebAssembly
// build), then transcodes each file's level 0 to RGBA32 with Binomial's own C++ transcoder
// (KTX2File in the same module): the references umbra's decoder must equal.
import BASIS from "./node_modules/ktx2-encoder/dist/basis/basis_encoder.js";
import fs from "node:fs";
const [src, out] = process.argv.slice(2);
const sizes = JSON.parse(fs.readFileSync(`${src}/sizes.json`));
const b = await BASIS(); b.initializeBasis();
const jobs = [
  // name, image, UASTC, Zstandard, mips, sRGB
  ["checker-etc1s-srgb-mips", "checker", false, false, true, true],
  ["bumps-uastc-zstd-mips", "bumps", true, true, true, false],
  ["metal-rough-uastc", "metal-rough", true, false, false, false],
  ["gradient-etc1s-alpha", "gradient", false, false, true, true],
  ["gradient-uastc-zstd-alpha", "gradient", true, true, false, true],
];
for (const [name, image, uastc, zstd, mips, srgb] of jobs) {
  const [w, h] = sizes[image];
  const rgba = new Uint8Array(fs.readFileSync(`${src}/${image}.rgba`));
  const e = new b.BasisEncoder();
  e.setCreateKTX2File(true);
  e.setUASTC(uastc);
  e.setKTX2UASTCSupercompression(zstd);
  e.setMipGen(mips);
  e.setPerceptual(srgb);
  (e.setKTX2AndBasisSRGBTransferFunc ?? e.setKTX2SRGBTransferFunc).call(e, srgb);
  if (!uastc) e.setQualityLevel(128);
  e.setSliceSourceImage(0, rgba, w, h, 0 /* raw RGBA */);
  const buf = new Uint8Array(w * h * 8 + 65536);
  const n = e.encode(buf);
  e.delete();
  if (n <= 0) throw new Error(`${name}: encode failed`);
  const ktx2 = buf.slice(0, n);
  fs.writeFileSync(`${out}/${name}.ktx2`, ktx2);
  const f = new b.KTX2File(ktx2);
  if (!f.isValid() || !f.startTranscoding()) throw new Error(`${name}: not transcodable`);
  const fmt = b.transcoder_texture_format.cTFRGBA32.value;
  const size = f.getImageTranscodedSizeInBytes(0, 0, 0, fmt);
  const pixels = new Uint8Array(size);
  if (!f.transcodeImage(pixels, 0, 0, 0, fmt, 0, -1, -1)) throw new Error(`${name}: transcode failed`);
  console.log(name, n, "bytes,", f.getLevels(), "levels,", f.getWidth(), "x", f.getHeight(), "etc1s", f.isETC1S(), "uastc", f.isUASTC(), "alpha", f.getHasAlpha());
  f.close(); f.delete();
  fs.writeFileSync(`${out}/${name}.rgba`, pixels); // prepare.py makes it ${name}.reference.png
}
