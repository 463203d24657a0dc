#!/usr/bin/env python3
"""Reference images of umbra's test scenes from an independent renderer, Mitsuba 3 (issue 24).

Each scene's glTF file is read here (the .glb reader of src/bin/umbra-bench/peers.py) and turned
into a Mitsuba scene that computes what the glTF specification says, without umbra's code:

- the glTF 2.0 metallic-roughness BRDF (Appendix B, with KHR_materials_ior and
  KHR_materials_specular) as a Python BSDF plugin, `GltfBsdf`: mix(dielectric, metal, metallic)
  with dielectric = (1 - max(F)) baseColor / pi + F D G / (4 |N.L| |N.V|), metal = the Schlick
  conductor Fresnel of baseColor times the same specular term, D and the separable Smith G from
  Mitsuba's own MicrofacetDistribution (GGX, or Beckmann for umbra's `--microfacet beckmann`);
  base colour (sRGB), metallic-roughness and normal textures with KHR_texture_transform, the
  sampler's wrap modes and magnification filter (level 0: the pixel jitter integrates the
  footprint), tangents from the file or from UV derivatives;
- KHR_materials_transmission in the same plugin, written from the extension texts and Walter et
  al. 2007: base = mix(diffuse, baseColor specular_btdf, transmission) under the same Fresnel
  mix; thin-walled (the specular lobe mirrored through the surface, at H_T), or with
  KHR_materials_volume (thickness above 0) Walter's refraction BTDF at H_TR with the extension's
  Fresnel (Schlick on the dense side's angle, total internal reflection);
- KHR_lights_punctual (point, spot with the specification's cone falloff, directional, the
  recommended range window) as a Python emitter, `PunctualLight`, intensity x colour taken as
  radiant intensity (irradiance for a directional light);
- emissive triangles (emissiveFactor x KHR_materials_emissive_strength) as Mitsuba `area`
  emitters (one-sided, like a glTF material that is not double-sided);
- an equirectangular environment map as a Python emitter, `LatLongEnvironment`: +Y up,
  u = atan2(d.x, -d.z) / 2 pi + 1/2, v = acos(d.y) / pi, row 0 at the top, each texel a constant
  cell (no interpolation), importance-sampled by luminance x sin(theta);
- the first camera (pinhole, vertical fov, the image's aspect ratio) with a box pixel filter
  (uniform jitter in the pixel), Mitsuba's `path` integrator with max_depth = bounces + 1 and no
  Russian roulette.

Each reference is K independent renders of N samples per pixel (seeds 0..K-1): the EXR holds the
mean of the K means (R, G, B) and the variance of that mean, the sample variance of the K means
divided by K (variance.R, variance.G, variance.B); a JSON beside it records the settings.

    nice -n 10 python3 tests/reference/mitsuba_refs.py             # every scene
    nice -n 10 python3 tests/reference/mitsuba_refs.py cornell     # some scenes
    nice -n 10 python3 tests/reference/mitsuba_refs.py --check-envmap spheres-sky
    nice -n 10 python3 tests/reference/mitsuba_refs.py --self-check spheres-sky
    nice -n 10 python3 tests/reference/mitsuba_refs.py --check-bsdf       # the transmission lobe's checks
    nice -n 10 python3 tests/reference/mitsuba_refs.py --compare-variant radiance-eta glass

Needs `pip install mitsuba numpy` and, for the llvm variant, apt's libllvm19. Not run in CI.
"""

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "src" / "bin" / "umbra-bench"))
from peers import accessor, node_matrix, read_glb  # noqa: E402

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402

mi.set_variant("llvm_ad_rgb")

SKY = "tests/reference/sky-128x64.exr"

# name: the glTF file, image size (the camera's aspect ratio), environment map, microfacet
# distribution, bounces (umbra's max_bounces), samples per render, renders.
SCENES = {
    "cornell": dict(gltf="scenes/cornell-box.glb", size=(48, 48), env=None, microfacet="ggx", bounces=8,
                    spp=2048, renders=32),
    "spheres-sky": dict(gltf="scenes/spheres.glb", size=(72, 48), env=SKY, microfacet="ggx", bounces=8,
                        spp=2048, renders=32),
    "spheres-sky-beckmann": dict(gltf="scenes/spheres.glb", size=(72, 48), env=SKY, microfacet="beckmann",
                                 bounces=8, spp=2048, renders=32),
    "textured": dict(gltf="scenes/textured.glb", size=(64, 48), env=None, microfacet="ggx", bounces=8,
                     spp=2048, renders=32),
    "glass": dict(gltf="scenes/glass.glb", size=(64, 48), env=SKY, microfacet="ggx", bounces=8, spp=2048,
                  renders=32),
}

OUT = ROOT / "tests" / "reference" / "mitsuba"

# Alternatives to the specification's transmission lobe, for measuring what a modelling choice
# changes (--compare-variant); the references never use them.
#   radiance-eta: the refraction BTDF times (eta_v / eta_t)^2, the radiance compression across
#     the boundary (Mitsuba's roughdielectric and umbra have it; the KHR_materials_volume formula
#     does not);
#   thin-literal-chi: the thin-walled BTDF's G1(L) on L itself, with the factor chi+(H_T.L / N.L)
#     that KHR_materials_transmission's (non-normative) implementation notes write, instead of on
#     L mirrored (see GltfBsdf.btdf).
VARIANTS = set()


# ---- glTF --------------------------------------------------------------------------------------

def srgb_decode(c):
    """The sRGB transfer function's inverse (IEC 61966-2-1) on values in [0, 1]."""
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def texture_transform(info):
    """KHR_texture_transform of a textureInfo as the 2x3 matrix T * R * S (glTF extension spec)."""
    t = info.get("extensions", {}).get("KHR_texture_transform", {})
    if "texCoord" in t:
        raise SystemExit("KHR_texture_transform.texCoord is not converted")
    ox, oy = t.get("offset", [0.0, 0.0])
    sx, sy = t.get("scale", [1.0, 1.0])
    r = t.get("rotation", 0.0)
    c, s = np.cos(r), np.sin(r)
    translation = np.array([[1, 0, ox], [0, 1, oy], [0, 0, 1]])
    rotation = np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]])
    scale = np.diag([sx, sy, 1.0])
    return (translation @ rotation @ scale)[:2]


class Gltf:
    """The parts of a .glb file the references use, in world space."""

    def __init__(self, path):
        self.doc, self.blob = read_glb(path)
        self.primitives, self.cameras, self.lights = [], [], []
        scene = self.doc["scenes"][self.doc.get("scene", 0)]
        for root in scene["nodes"]:
            self.walk(root, np.eye(4))

    def data(self, index):
        a = self.doc["accessors"][index]
        view = self.doc["bufferViews"][a["bufferView"]]
        if a.get("normalized") or "byteStride" in view or a.get("sparse"):
            raise SystemExit(f"accessor {index}: strided, normalized or sparse accessors are not converted")
        return np.asarray(accessor(self.doc, self.blob, index), dtype=np.float64)

    def walk(self, index, parent):
        node = self.doc["nodes"][index]
        world = parent @ node_matrix(node)
        if "camera" in node:
            self.cameras.append((world, self.doc["cameras"][node["camera"]]))
        light = node.get("extensions", {}).get("KHR_lights_punctual")
        if light is not None:
            lights = self.doc["extensions"]["KHR_lights_punctual"]["lights"]
            self.lights.append((world, lights[light["light"]]))
        for prim in self.doc["meshes"][node["mesh"]]["primitives"] if "mesh" in node else []:
            self.primitives.append(self.primitive(prim, world, f"node{index}-{len(self.primitives)}"))
        for child in node.get("children", []):
            self.walk(child, world)

    def primitive(self, prim, world, name):
        if prim.get("mode", 4) != 4:
            raise SystemExit(f"{name}: only triangle lists are converted")
        attributes = prim["attributes"]
        m3 = world[:3, :3]
        positions = self.data(attributes["POSITION"]) @ m3.T + world[:3, 3]
        faces = self.data(prim["indices"]).astype(np.int64).reshape(-1, 3)
        if np.linalg.det(m3) < 0:
            faces = faces[:, ::-1]  # front faces stay counter-clockwise
        if "NORMAL" not in attributes:
            raise SystemExit(f"{name}: primitives without normals are not converted")
        normals = self.data(attributes["NORMAL"]) @ np.linalg.inv(m3)
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        uv = [self.data(attributes[k]) if k in attributes else np.zeros((len(positions), 2))
              for k in ("TEXCOORD_0", "TEXCOORD_1")]
        material = self.doc["materials"][prim["material"]] if "material" in prim else {}
        tangents = None
        if "normalTexture" in material:
            if "TANGENT" in attributes:
                t = self.data(attributes["TANGENT"])
                xyz = t[:, :3] @ m3.T
                sign = np.where(t[:, 3] < 0, -1.0, 1.0)
            else:
                xyz, sign = uv_tangents(positions, normals, uv[material["normalTexture"].get("texCoord", 0)], faces)
            xyz = xyz - normals * np.sum(xyz * normals, axis=1, keepdims=True)
            xyz /= np.linalg.norm(xyz, axis=1, keepdims=True)
            tangents = np.c_[xyz, sign]
        return dict(name=name, positions=positions, normals=normals, uv0=uv[0], uv1=uv[1], faces=faces,
                    tangents=tangents, material=material)

    def image(self, index, srgb):
        """Image `index` as linear float RGBA (rows top first)."""
        img = self.doc["images"][index]
        view = self.doc["bufferViews"][img["bufferView"]]
        start = view.get("byteOffset", 0)
        with tempfile.NamedTemporaryFile(suffix=".png") as f:
            f.write(self.blob[start:start + view["byteLength"]])
            f.flush()
            bitmap = mi.Bitmap(f.name)
        raw = np.array(bitmap)
        if raw.dtype != np.uint8:
            raise SystemExit(f"image {index}: only 8-bit images are converted")
        raw = raw.reshape(raw.shape[0], raw.shape[1], -1).astype(np.float64) / 255.0
        channels = raw.shape[2]
        rgb = raw[:, :, :3] if channels >= 3 else np.repeat(raw[:, :, :1], 3, axis=2)
        alpha = raw[:, :, 3:4] if channels in (2, 4) else np.ones(raw.shape[:2] + (1,))
        if channels == 2:
            alpha = raw[:, :, 1:2]
        if srgb:
            rgb = srgb_decode(rgb)
        return np.concatenate([rgb, alpha], axis=2)


def uv_tangents(positions, normals, uv, faces):
    """Tangents where the file has none (glTF: MikkTSpace, which on the flat, unwelded faces of
    the test scenes is each face's UV derivative): T along dP/du, the bitangent's sign such that
    cross(N, T) * w points "up" in the image, i.e. along -dP/dv (UVs grow downwards)."""
    du = np.zeros_like(positions)
    dv = np.zeros_like(positions)
    for a, b, c in faces:
        e1, e2 = positions[b] - positions[a], positions[c] - positions[a]
        d1, d2 = uv[b] - uv[a], uv[c] - uv[a]
        det = d1[0] * d2[1] - d1[1] * d2[0]
        if det == 0:
            continue
        tu = (e1 * d2[1] - e2 * d1[1]) / det
        tv = (e2 * d1[0] - e1 * d2[0]) / det
        for v in (a, b, c):
            du[v] += tu
            dv[v] += tv
    sign = np.where(np.sum(np.cross(normals, du) * -dv, axis=1) < 0, -1.0, 1.0)
    return du, sign


# ---- the glTF BSDF -----------------------------------------------------------------------------

WRAP = {10497: 0, 33071: 1, 33648: 2}  # REPEAT, CLAMP_TO_EDGE, MIRRORED_REPEAT


class Texture:
    """One texture slot: linear RGBA texels, the sampler's wrap modes and magnification filter,
    and the slot's transform."""

    def __init__(self, gltf, info, srgb):
        tex = gltf.doc["textures"][info["index"]]
        sampler = gltf.doc["samplers"][tex["sampler"]] if "sampler" in tex else {}
        rgba = gltf.image(tex["source"], srgb)
        self.h, self.w = rgba.shape[:2]
        self.texels = mi.Vector4f(*[mi.Float(rgba[:, :, c].ravel().astype(np.float32)) for c in range(4)])
        self.wrap = (WRAP[sampler.get("wrapS", 10497)], WRAP[sampler.get("wrapT", 10497)])
        self.linear = sampler.get("magFilter", 9729) != 9728  # NEAREST: 9728; LINEAR or unset
        self.matrix = [[float(x) for x in row] for row in texture_transform(info)]
        self.texcoord = info.get("texCoord", 0)

    def wrap_index(self, i, n, mode):
        if mode == 1:
            return dr.clip(i, 0, n - 1)
        if mode == 2:
            m = i - 2 * n * dr.floor(i / (2 * n))
            return dr.select(m < n, m, 2 * n - 1 - m)
        return i - n * dr.floor(i / n)

    def texel(self, x, y):
        x = self.wrap_index(x, self.w, self.wrap[0])
        y = self.wrap_index(y, self.h, self.wrap[1])
        return dr.gather(mi.Vector4f, self.texels, mi.UInt32(y * self.w + x))

    def eval(self, uv0, uv1):
        st = uv1 if self.texcoord == 1 else uv0
        m = self.matrix
        u = m[0][0] * st.x + m[0][1] * st.y + m[0][2]
        v = m[1][0] * st.x + m[1][1] * st.y + m[1][2]
        if not self.linear:
            return self.texel(dr.floor(u * self.w), dr.floor(v * self.h))
        x, y = u * self.w - 0.5, v * self.h - 0.5
        x0, y0 = dr.floor(x), dr.floor(y)
        fx, fy = x - x0, y - y0
        top = dr.lerp(self.texel(x0, y0), self.texel(x0 + 1, y0), fx)
        bottom = dr.lerp(self.texel(x0, y0 + 1), self.texel(x0 + 1, y0 + 1), fx)
        return dr.lerp(top, bottom, fy)


def luminance(c):
    return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z


def max3(c):
    return dr.maximum(c.x, dr.maximum(c.y, c.z))


class GltfBsdf(mi.BSDF):
    """The glTF metallic-roughness material of one primitive, with KHR_materials_ior, _specular,
    _transmission and _volume (no attenuation). Mitsuba's shading frame is ignored:
    the mesh is loaded with face normals only, and the BSDF builds the glTF shading frame itself
    from the primitive's vertex data at the hit (interpolated normal on the viewer's side,
    normal-mapped through the tangent frame where that stays above the surface). Reflected light
    must arrive above both the shading and the geometric surface, transmitted light below both
    (the two normals must agree about the side, as for a ray leaving the surface). A volume's
    outside is the side its triangles' winding faces (KHR_materials_volume: closed meshes whose
    normals point out)."""

    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        sides = mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide
        self.m_components = [mi.BSDFFlags.GlossyReflection | sides, mi.BSDFFlags.DiffuseReflection | sides,
                             mi.BSDFFlags.GlossyTransmission | sides]
        self.m_flags = (mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.GlossyReflection
                        | mi.BSDFFlags.GlossyTransmission | sides)

    def setup(self, gltf, prim, microfacet):
        """Called after construction with the primitive and the material."""
        f32 = lambda a: mi.Float(np.ascontiguousarray(a, dtype=np.float32).ravel())  # noqa: E731
        self.positions = f32(prim["positions"])
        self.normals = f32(prim["normals"])
        self.uv0, self.uv1 = f32(prim["uv0"]), f32(prim["uv1"])
        self.faces = mi.UInt32(np.ascontiguousarray(prim["faces"], dtype=np.uint32).ravel())
        self.tangents = f32(prim["tangents"]) if prim["tangents"] is not None else None
        self.beckmann = microfacet == "beckmann"
        m = prim["material"]
        if m.get("alphaMode", "OPAQUE") != "OPAQUE":
            raise SystemExit(f"{prim['name']}: alpha modes other than OPAQUE are not converted")
        ext = m.get("extensions", {})
        transmission = ext.get("KHR_materials_transmission", {})
        volume = ext.get("KHR_materials_volume", {})
        if "transmissionTexture" in transmission:
            raise SystemExit(f"{prim['name']}: transmission textures are not converted")
        if volume.get("attenuationDistance", float("inf")) != float("inf"):
            raise SystemExit(f"{prim['name']}: KHR_materials_volume's attenuation is not converted")
        # KHR_materials_transmission: the share of the light that is not specularly reflected
        # which crosses the surface; KHR_materials_volume with a thickness above 0: the surface
        # bounds a volume of index `ior` (refraction), else thin-walled.
        self.transmission = transmission.get("transmissionFactor", 0.0)
        self.volume = volume.get("thicknessFactor", 0.0) > 0
        pbr = m.get("pbrMetallicRoughness", {})
        self.base_factor = mi.Color3f(*pbr.get("baseColorFactor", [1, 1, 1, 1])[:3])
        self.metallic_factor = pbr.get("metallicFactor", 1.0)
        self.roughness_factor = pbr.get("roughnessFactor", 1.0)
        ior = ext.get("KHR_materials_ior", {}).get("ior", 1.5)
        if self.volume and ior == 1:
            raise SystemExit(f"{prim['name']}: a volume of ior 1 (no refracting boundary) is not converted")
        self.ior = ior
        spec = ext.get("KHR_materials_specular", {})
        if "specularTexture" in spec or "specularColorTexture" in spec:
            raise SystemExit(f"{prim['name']}: specular textures are not converted")
        self.specular = spec.get("specularFactor", 1.0)
        f0 = ((ior - 1) / (ior + 1)) ** 2
        self.f0 = mi.Color3f(*[min(f0 * c, 1.0) * self.specular for c in spec.get("specularColorFactor", [1, 1, 1])])
        self.base_texture = Texture(gltf, pbr["baseColorTexture"], True) if "baseColorTexture" in pbr else None
        self.mr_texture = (Texture(gltf, pbr["metallicRoughnessTexture"], False)
                           if "metallicRoughnessTexture" in pbr else None)
        normal = m.get("normalTexture")
        self.normal_texture = Texture(gltf, normal, False) if normal else None
        self.normal_scale = normal.get("scale", 1.0) if normal else 1.0
        return self

    # The hit: barycentrics, frame and material.
    def hit(self, si):
        i = [dr.gather(mi.UInt32, self.faces, si.prim_index * 3 + k) for k in range(3)]
        p = [dr.gather(mi.Vector3f, self.positions, v) for v in i]
        e1, e2 = p[1] - p[0], p[2] - p[0]
        ng = dr.normalize(dr.cross(e1, e2))
        d = si.p - p[0]
        d00, d01, d11 = dr.dot(e1, e1), dr.dot(e1, e2), dr.dot(e2, e2)
        d20, d21 = dr.dot(d, e1), dr.dot(d, e2)
        denom = d00 * d11 - d01 * d01
        b1 = (d11 * d20 - d01 * d21) / denom
        b2 = (d00 * d21 - d01 * d20) / denom
        b = [1 - b1 - b2, b1, b2]
        lerp = lambda arr, t: sum((dr.gather(t, arr, v) * w for v, w in zip(i, b)), t(0))  # noqa: E731
        wo = si.to_world(si.wi)
        front = dr.dot(ng, wo) >= 0  # the outside of a volume: glTF's winding faces out
        ng = dr.select(front, ng, -ng)
        n = lerp(self.normals, mi.Vector3f)
        n_len = dr.norm(n)
        n = dr.select(n_len > 0, n / n_len, ng)
        n = dr.select(dr.dot(n, ng) < 0, -n, n)
        uv0, uv1 = lerp(self.uv0, mi.Point2f), lerp(self.uv1, mi.Point2f)
        if self.normal_texture is not None:
            t4 = lerp(self.tangents, mi.Vector4f)
            w0 = dr.gather(mi.Vector4f, self.tangents, i[0]).w
            tg = mi.Vector3f(t4.x, t4.y, t4.z)
            tt = tg - n * dr.dot(n, tg)
            tl = dr.norm(tt)
            tt = tt / tl
            bt = dr.cross(n, tt) * dr.select(w0 < 0, -1.0, 1.0)
            tex = self.normal_texture.eval(uv0, uv1)
            nm = mi.Vector3f(tex.x, tex.y, tex.z) * 2 - 1
            nm = mi.Vector3f(nm.x * self.normal_scale, nm.y * self.normal_scale, nm.z)
            mapped = dr.normalize(nm.x * tt + nm.y * bt + nm.z * n)
            ok = (tl > 1e-8) & dr.isfinite(mapped.x) & (dr.dot(mapped, ng) > 0)
            n = dr.select(ok, mapped, n)
        frame = mi.Frame3f(n)
        base = self.base_factor
        if self.base_texture is not None:
            t = self.base_texture.eval(uv0, uv1)
            base = base * mi.Color3f(t.x, t.y, t.z)
        metallic, roughness = mi.Float(self.metallic_factor), mi.Float(self.roughness_factor)
        if self.mr_texture is not None:
            t = self.mr_texture.eval(uv0, uv1)
            metallic, roughness = metallic * t.z, roughness * t.y
        metallic, roughness = dr.clip(metallic, 0, 1), dr.clip(roughness, 0, 1)
        alpha = dr.maximum(roughness * roughness, 1e-4)
        kind = mi.MicrofacetType.Beckmann if self.beckmann else mi.MicrofacetType.GGX
        distr = mi.MicrofacetDistribution(kind, alpha, True)
        # Indices of refraction on the viewer's side and across the boundary (1 and 1 when thin).
        eta_v = dr.select(front, 1.0, self.ior) if self.volume else mi.Float(1)
        eta_t = dr.select(front, self.ior, 1.0) if self.volume else mi.Float(1)
        return dict(ng=ng, frame=frame, wo=frame.to_local(wo), base=base, metallic=metallic, distr=distr,
                    eta_v=eta_v, eta_t=eta_t)

    def fresnel(self, f0, f90, c):
        m = dr.clip(1 - c, 0, 1)
        return f0 + (f90 - f0) * (m * m * m * m * m)

    def dielectric_fresnel(self, h, c):
        """The dielectric's F at a microfacet with |V.H| = c. Thin-walled, or entering the denser
        side: Schlick at c. KHR_materials_volume, leaving the denser side (eta_v > eta_t): Schlick
        at the transmitted side's cosine, sin^2 = (eta_v / eta_t)^2 (1 - c^2), and 1 (total
        internal reflection, F90 unscaled by KHR_materials_specular) where that reaches 1."""
        f90 = mi.Color3f(self.specular)
        if not self.volume:
            return self.fresnel(self.f0, f90, c)
        ratio = h["eta_v"] / h["eta_t"]
        sin2_t = ratio * ratio * (1 - c * c)
        leaving = h["eta_v"] > h["eta_t"]
        f = self.fresnel(self.f0, f90, dr.select(leaving, dr.safe_sqrt(1 - sin2_t), c))
        return dr.select(leaving & (sin2_t >= 1), mi.Color3f(1), f)

    def brdf(self, h, wi):
        """f(wo, wi) * |N.L| for wi above the surface in the shading frame (wo = h["wo"]): glTF's
        fresnel_mix(layer = specular_brdf, base = mix(diffuse_brdf, specular_btdf * baseColor,
        transmission)), whose BTDF is 0 above; 0 below either normal."""
        wo = h["wo"]
        half = dr.normalize(wo + wi)
        oh = dr.maximum(dr.dot(wo, half), 0)
        distr = h["distr"]
        spec = distr.eval(half) * distr.G(wo, wi, half) / (4 * wo.z * wi.z)
        f_dielectric = self.dielectric_fresnel(h, oh)
        diffuse = (1 - self.transmission) * h["base"] * dr.inv_pi
        dielectric = (1 - max3(f_dielectric)) * diffuse + f_dielectric * spec
        metal = self.fresnel(h["base"], mi.Color3f(1), oh) * spec
        f = dr.lerp(dielectric, metal, h["metallic"])
        above = (wo.z > 0) & (wi.z > 0) & (dr.dot(h["frame"].to_world(wi), h["ng"]) > 0)
        return dr.select(above, f * wi.z, 0)

    def transmission_half(self, h, wi):
        """The half vector of a transmission to wi (below), facing +z: thin-walled (KHR_materials_
        transmission), H_T = normalize(V - 2 (N.L) N + L), L mirrored to V's side; a volume
        boundary (KHR_materials_volume, Walter et al. 2007 eq. 16), H_TR = -normalize(eta_v V +
        eta_t L)."""
        wo = h["wo"]
        if not self.volume:
            return dr.normalize(wo + mi.Vector3f(wi.x, wi.y, -wi.z))
        m = dr.normalize(-(h["eta_v"] * wo + h["eta_t"] * wi))
        return dr.select(m.z < 0, -m, m)

    def btdf(self, h, wi):
        """f(wo, wi) * |N.L| for wi below the surface: (1 - metallic) (1 - max F) transmission
        baseColor specular_btdf, F at the transmission half vector. G is the separable Smith
        G1(V) G1(L), each with its chi+(H.X / N.X). Thin-walled (KHR_materials_transmission):
        D G / (4 |N.L| |N.V|) at H_T, "exactly the same as the specular lobe except sampled along
        the line of sight through the surface", so G1 takes L mirrored to the viewer's side, as
        the specular lobe would (the extension's non-normative notes write chi+(H_T.L / N.L) of L
        itself, which also removes light arriving on a microfacet's front: --compare-variant
        thin-literal-chi). A volume boundary (KHR_materials_volume): Walter et al.'s
        |H.L| |H.V| / (|N.L| |N.V|) eta_t^2 G D / (eta_v H.V + eta_t H.L)^2 at H_TR. 0 unless wi
        is below both normals."""
        wo = h["wo"]
        distr = h["distr"]
        m = self.transmission_half(h, wi)
        vh, lh = dr.dot(wo, m), dr.dot(wi, m)
        if self.volume or "thin-literal-chi" in VARIANTS:
            dg = distr.eval(m) * distr.smith_g1(wo, m) * distr.smith_g1(wi, m)
        else:
            dg = distr.eval(m) * distr.smith_g1(wo, m) * distr.smith_g1(mi.Vector3f(wi.x, wi.y, -wi.z), m)
        if self.volume:
            denom = h["eta_v"] * vh + h["eta_t"] * lh
            f = dr.abs(lh * vh) * h["eta_t"] * h["eta_t"] * dg / (wo.z * -wi.z * denom * denom)
            f = dr.select(denom != 0, f, 0)
            if "radiance-eta" in VARIANTS:
                f *= (h["eta_v"] / h["eta_t"]) ** 2
        else:
            f = dg / (4 * wo.z * -wi.z)
        f_dielectric = self.dielectric_fresnel(h, dr.abs(vh))
        value = (1 - h["metallic"]) * self.transmission * (1 - max3(f_dielectric)) * h["base"] * f
        below = (wo.z > 0) & (wi.z < 0) & (dr.dot(h["frame"].to_world(wi), h["ng"]) < 0)
        return dr.select(below, value * -wi.z, 0)

    def bsdf(self, h, wi):
        """f(wo, wi) * |N.L|, either side."""
        if self.transmission == 0:
            return self.brdf(h, wi)
        return dr.select(wi.z < 0, self.btdf(h, wi), self.brdf(h, wi))

    def lobe_probabilities(self, h):
        """Probabilities of the specular, transmission and diffuse lobes: their Fresnel-weighted
        albedos at wo (the transmission's the remainder, so that a diffuse share of 0 is never
        sampled). F is 9:1 the dielectric's at N.V (with total internal reflection) and Schlick's
        plain, so that transmission keeps a probability beyond the critical angle, where tilted
        microfacets still refract, and reflection a large one there. This only shapes the noise."""
        wo_z = h["wo"].z
        plain = self.fresnel(self.f0, mi.Color3f(self.specular), wo_z)
        f = 0.9 * max3(self.dielectric_fresnel(h, wo_z)) + 0.1 * max3(plain)
        spec = dr.lerp(f, 1, h["metallic"])
        rest = (1 - h["metallic"]) * (1 - f) * luminance(h["base"])
        diffuse = rest * (1 - self.transmission)
        total = spec + rest
        p_spec = dr.select(total > 0, spec / total, 0.5)
        p_diffuse = dr.select(total > 0, diffuse / total, 0.5)
        return p_spec, 1 - p_spec - p_diffuse, p_diffuse

    def transmission_density(self, h, wi):
        """Solid-angle density of wi (below) under the transmission lobe's sampling: visible
        normals m, then wi mirrored from the reflection (thin) or refracted (Walter et al. eq. 17:
        |dm/dwi| = eta_t^2 |wi.m| / (eta_v wo.m + eta_t wi.m)^2)."""
        wo = h["wo"]
        m = self.transmission_half(h, wi)
        pdf_m = h["distr"].pdf(wo, m)
        if not self.volume:
            vh = dr.dot(wo, m)
            return dr.select(vh > 0, pdf_m / (4 * vh), 0)
        vh, lh = dr.dot(wo, m), dr.dot(wi, m)
        denom = h["eta_v"] * vh + h["eta_t"] * lh
        pdf = pdf_m * h["eta_t"] * h["eta_t"] * dr.abs(lh) / (denom * denom)
        return dr.select((vh > 0) & (lh < 0) & (denom != 0), pdf, 0)

    def density(self, h, wi):
        wo = h["wo"]
        half = dr.normalize(wo + wi)
        oh = dr.dot(wo, half)
        p_spec, p_trans, p_diffuse = self.lobe_probabilities(h)
        spec = dr.select(oh > 0, h["distr"].pdf(wo, half) / (4 * oh), 0)
        pdf = p_spec * spec + p_diffuse * mi.warp.square_to_cosine_hemisphere_pdf(wi)
        pdf = dr.select(wi.z > 0, pdf, 0)
        if self.transmission > 0:
            pdf = dr.select(wi.z < 0, p_trans * self.transmission_density(h, wi), pdf)
        return dr.select(wo.z > 0, pdf, 0)

    def sample_direction(self, h, sample1, sample2):
        """wi by the lobe choice (sample1) and its sample (sample2), which lobe, and whether wi
        lies on that lobe's side."""
        wo = h["wo"]
        m, _ = h["distr"].sample(wo, sample2)
        reflected = 2 * dr.dot(wo, m) * m - wo
        diffuse = mi.warp.square_to_cosine_hemisphere(sample2)
        p_spec, _, p_diffuse = self.lobe_probabilities(h)
        specular = sample1 < p_spec
        transmitted = ~specular & (sample1 < 1 - p_diffuse)
        wi = dr.select(specular, reflected, diffuse)
        if self.transmission > 0:
            if self.volume:
                # Snell's law through m (eta = eta_v / eta_t; none beyond the critical angle).
                eta = h["eta_v"] / h["eta_t"]
                c = dr.dot(wo, m)
                sin2_t = eta * eta * (1 - c * c)
                through = (eta * c - dr.safe_sqrt(1 - sin2_t)) * m - eta * wo
                through = dr.select(sin2_t < 1, through, mi.Vector3f(0, 0, 1))
            else:
                through = mi.Vector3f(reflected.x, reflected.y, -reflected.z)
            wi = dr.select(transmitted, through, wi)
        valid = dr.select(transmitted, wi.z < 0, wi.z > 0)
        return wi, specular, transmitted, valid

    def sample(self, ctx, si, sample1, sample2, active=True):
        h = self.hit(si)
        wi, specular, transmitted, valid = self.sample_direction(h, sample1, sample2)
        pdf = self.density(h, wi)
        value = self.bsdf(h, wi)
        bs = dr.zeros(mi.BSDFSample3f)
        bs.wo = si.to_local(h["frame"].to_world(wi))
        bs.pdf = pdf
        bs.eta = dr.select(transmitted, h["eta_t"] / h["eta_v"], 1.0)
        bs.sampled_type = dr.select(specular, mi.UInt32(+mi.BSDFFlags.GlossyReflection),
                                    dr.select(transmitted, mi.UInt32(+mi.BSDFFlags.GlossyTransmission),
                                              mi.UInt32(+mi.BSDFFlags.DiffuseReflection)))
        bs.sampled_component = dr.select(specular, mi.UInt32(0), dr.select(transmitted, mi.UInt32(2), mi.UInt32(1)))
        ok = active & valid & (pdf > 0) & (h["wo"].z > 0)
        return bs, dr.select(ok, value / pdf, 0)

    def eval(self, ctx, si, wo, active=True):
        h = self.hit(si)
        return self.bsdf(h, h["frame"].to_local(si.to_world(wo)))

    def pdf(self, ctx, si, wo, active=True):
        h = self.hit(si)
        return self.density(h, h["frame"].to_local(si.to_world(wo)))

    def eval_pdf(self, ctx, si, wo, active=True):
        h = self.hit(si)
        wi = h["frame"].to_local(si.to_world(wo))
        return self.bsdf(h, wi), self.density(h, wi)

    def traverse(self, callback):
        pass

    def to_string(self):
        return "GltfBsdf"


# ---- emitters ----------------------------------------------------------------------------------

class Emitter(mi.Emitter):
    """What a Python emitter must answer but the path integrator never asks of these."""

    def sample_ray(self, *args):
        return dr.zeros(mi.Ray3f), mi.Color3f(0)

    def sample_position(self, *args):
        return dr.zeros(mi.PositionSample3f), mi.Float(0)

    def bbox(self):
        return mi.ScalarBoundingBox3f()

    def traverse(self, callback):
        pass


class PunctualLight(Emitter):
    """A KHR_lights_punctual light: intensity x colour / d^2 (point, spot) with the range window
    clamp(1 - (d / range)^4, 0, 1)^2 when a range is given and the spot's
    clamp((cos - cos_outer) / (cos_inner - cos_outer), 0, 1)^2; a directional light's intensity x
    colour is irradiance. `radius`: beyond the scene (where a directional light's shadow ray ends)."""

    def __init__(self, props):
        Emitter.__init__(self, props)

    def setup(self, world, light, radius):
        self.kind = light["type"]
        self.intensity = mi.Color3f(*[c * light.get("intensity", 1.0) for c in light.get("color", [1, 1, 1])])
        self.position = mi.Point3f(*[float(x) for x in world[:3, 3]])
        d = world[:3, :3] @ np.array([0.0, 0.0, -1.0])
        self.direction = mi.Vector3f(*[float(x) for x in d / np.linalg.norm(d)])
        self.range = light.get("range", 0.0)
        spot = light.get("spot", {})
        self.cos_outer = float(np.cos(spot.get("outerConeAngle", np.pi / 4)))
        self.cos_inner = float(np.cos(spot.get("innerConeAngle", 0.0)))
        self.radius = radius
        self.m_flags = mi.EmitterFlags.DeltaDirection if self.kind == "directional" else mi.EmitterFlags.DeltaPosition
        return self

    def sample_direction(self, it, sample, active=True):
        ds = dr.zeros(mi.DirectionSample3f)
        if self.kind == "directional":
            wi = -self.direction
            ds.p = it.p + wi * (2 * self.radius)
            ds.dist = 2 * self.radius
            weight = self.intensity
        else:
            to_light = self.position - it.p
            dist = dr.norm(to_light)
            wi = to_light / dist
            ds.p = self.position
            ds.dist = dist
            attenuation = 1 / (dist * dist)
            if self.range > 0:
                r = dist / self.range
                window = dr.clip(1 - r * r * r * r, 0, 1)
                attenuation *= window * window
            if self.kind == "spot":
                c = dr.dot(-wi, self.direction)
                spot = dr.clip((c - self.cos_outer) / (self.cos_inner - self.cos_outer), 0, 1)
                attenuation *= spot * spot
            weight = self.intensity * attenuation
        ds.d = wi
        ds.n = -wi
        ds.pdf = 1.0
        ds.delta = True
        ds.time = it.time
        ds.emitter = mi.EmitterPtr(self)
        return ds, weight

    def pdf_direction(self, it, ds, active=True):
        return mi.Float(0)

    def eval_direction(self, it, ds, active=True):
        return mi.Color3f(0)

    def eval(self, si, active=True):
        return mi.Color3f(0)

    def to_string(self):
        return f"PunctualLight[{self.kind}]"


def env_uv(d):
    return mi.Point2f(dr.atan2(d.x, -d.z) * (0.5 * dr.inv_pi) + 0.5, dr.safe_acos(d.y) * dr.inv_pi)


def env_direction(uv):
    phi = (uv.x - 0.5) * 2 * dr.pi
    theta = uv.y * dr.pi
    s = dr.sin(theta)
    return mi.Vector3f(s * dr.sin(phi), dr.cos(theta), -s * dr.cos(phi))


class LatLongEnvironment(Emitter):
    """An equirectangular map of constant cells: direction d looks up texel
    (floor(u W), floor(v H)) with u = atan2(d.x, -d.z) / 2 pi + 1/2, v = acos(d.y) / pi.
    Sampled by luminance x sin(theta at the texel centre), uniform in (u, v) within the texel."""

    def __init__(self, props):
        Emitter.__init__(self, props)
        self.m_flags = mi.EmitterFlags.Infinite | mi.EmitterFlags.SpatiallyVarying

    def setup(self, texels, radius):
        self.h, self.w = texels.shape[:2]
        self.radius = radius
        self.texels = mi.Color3f(*[mi.Float(texels[:, :, c].ravel().astype(np.float32)) for c in range(3)])
        theta = (np.arange(self.h) + 0.5) / self.h * np.pi
        weight = (0.2126 * texels[:, :, 0] + 0.7152 * texels[:, :, 1] + 0.0722 * texels[:, :, 2])
        weight = weight * np.sin(theta)[:, None]
        if weight.sum() <= 0:
            weight = np.ones_like(weight)
        pdf_uv = weight / weight.sum() * (self.w * self.h)
        self.pdf_uv = mi.Float(pdf_uv.ravel().astype(np.float32))
        self.distr = mi.DiscreteDistribution(weight.ravel().astype(np.float32))
        return self

    def texel(self, uv):
        x = dr.minimum(mi.UInt32(dr.maximum(uv.x * self.w, 0)), self.w - 1)
        y = dr.minimum(mi.UInt32(dr.maximum(uv.y * self.h, 0)), self.h - 1)
        return y * self.w + x

    def radiance(self, d):
        return dr.gather(mi.Color3f, self.texels, self.texel(env_uv(d)))

    def density(self, d):
        s = dr.sqrt(dr.maximum(0, 1 - d.y * d.y))
        p = dr.gather(mi.Float, self.pdf_uv, self.texel(env_uv(d)))
        return dr.select(s > 0, p / (2 * dr.pi * dr.pi * s), 0)

    def eval(self, si, active=True):
        return self.radiance(-si.wi)

    def sample_direction(self, it, sample, active=True):
        index, reused = self.distr.sample_reuse(sample.x)
        x, y = index % self.w, index // self.w
        uv = mi.Point2f((mi.Float(x) + reused) / self.w, (mi.Float(y) + sample.y) / self.h)
        d = env_direction(uv)
        s = dr.sin(uv.y * dr.pi)
        pdf = dr.select(s > 0, dr.gather(mi.Float, self.pdf_uv, index) / (2 * dr.pi * dr.pi * s), 0)
        ds = dr.zeros(mi.DirectionSample3f)
        ds.p = it.p + d * (2 * self.radius)
        ds.n = -d
        ds.uv = uv
        ds.d = d
        ds.dist = 2 * self.radius
        ds.pdf = pdf
        ds.delta = False
        ds.time = it.time
        ds.emitter = mi.EmitterPtr(self)
        radiance = dr.gather(mi.Color3f, self.texels, index)
        return ds, dr.select(pdf > 0, radiance / pdf, 0)

    def pdf_direction(self, it, ds, active=True):
        return self.density(ds.d)

    def eval_direction(self, it, ds, active=True):
        return self.radiance(ds.d)

    def to_string(self):
        return f"LatLongEnvironment[{self.w}x{self.h}]"


mi.register_bsdf("gltf_bsdf", GltfBsdf)
mi.register_emitter("gltf_punctual", PunctualLight)
mi.register_emitter("latlong_environment", LatLongEnvironment)


# ---- the scene ---------------------------------------------------------------------------------

def read_env(path):
    return np.array(mi.Bitmap(str(ROOT / path)), dtype=np.float64)[:, :, :3]


def mitsuba_scene(spec, work, builtin_envmap=False):
    """The Mitsuba scene of `spec` (an entry of SCENES); PLY files go to `work`."""
    gltf = Gltf(ROOT / spec["gltf"])
    lo = np.min([p["positions"].min(axis=0) for p in gltf.primitives], axis=0)
    hi = np.max([p["positions"].max(axis=0) for p in gltf.primitives], axis=0)
    radius = float(np.linalg.norm(hi - lo))
    scene = {"type": "scene",
             "integrator": {"type": "path", "max_depth": spec["bounces"] + 1, "rr_depth": 1 << 20}}
    for prim in gltf.primitives:
        mesh = mi.Mesh(prim["name"], len(prim["positions"]), len(prim["faces"]), has_vertex_normals=False)
        params = mi.traverse(mesh)
        params["vertex_positions"] = mi.Float(prim["positions"].astype(np.float32).ravel())
        params["faces"] = mi.UInt32(prim["faces"].astype(np.uint32).ravel())
        params.update()
        ply = work / f"{prim['name']}.ply"
        mesh.write_ply(str(ply))
        bsdf = mi.load_dict({"type": "gltf_bsdf"}).setup(gltf, prim, spec["microfacet"])
        shape = {"type": "ply", "filename": str(ply), "face_normals": True, "bsdf": bsdf}
        m = prim["material"]
        if "emissiveTexture" in m or m.get("doubleSided", False) and any(m.get("emissiveFactor", [0, 0, 0])):
            raise SystemExit(f"{prim['name']}: emissive textures and double-sided emitters are not converted")
        strength = m.get("extensions", {}).get("KHR_materials_emissive_strength", {}).get("emissiveStrength", 1.0)
        emissive = [strength * e for e in m.get("emissiveFactor", [0, 0, 0])]
        if any(emissive):
            shape["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": emissive}}
        scene[prim["name"]] = shape
    for k, (world, light) in enumerate(gltf.lights):
        scene[f"light{k}"] = mi.load_dict({"type": "gltf_punctual"}).setup(world, light, radius)
    if spec["env"]:
        if builtin_envmap:
            # Mitsuba's own envmap (bilinear between texel samples): u is umbra's u - 1/2, so a half
            # turn about +Y maps one onto the other.
            scene["environment"] = {"type": "envmap", "filename": str(ROOT / spec["env"]),
                                    "to_world": mi.ScalarTransform4f().rotate([0, 1, 0], 180)}
        else:
            scene["environment"] = mi.load_dict({"type": "latlong_environment"}).setup(read_env(spec["env"]), radius)
    if not gltf.cameras:
        raise SystemExit(f"{spec['gltf']}: the scene has no camera")
    world, cam = gltf.cameras[0]
    if cam.get("type") != "perspective":
        raise SystemExit(f"{spec['gltf']}: the first camera is not perspective")
    origin = world[:3, 3]
    forward = world[:3, :3] @ np.array([0.0, 0.0, -1.0])
    up = world[:3, :3] @ np.array([0.0, 1.0, 0.0])
    w, h = spec["size"]
    scene["sensor"] = {
        "type": "perspective", "fov_axis": "y", "fov": float(np.degrees(cam["perspective"]["yfov"])),
        "near_clip": 1e-4,
        "to_world": mi.ScalarTransform4f().look_at(origin=origin.tolist(), target=(origin + forward).tolist(),
                                                   up=up.tolist()),
        "film": {"type": "hdrfilm", "width": w, "height": h, "rfilter": {"type": "box"}, "pixel_format": "rgb"},
        "sampler": {"type": "independent"},
    }
    return mi.load_dict(scene)


def render(scene, spec):
    """K renders of N spp: per pixel the mean of the means and the variance of that mean."""
    means = []
    for seed in range(spec["renders"]):
        image = mi.render(scene, spp=spec["spp"], seed=seed)
        means.append(np.array(image, dtype=np.float64)[:, :, :3])
    means = np.stack(means)
    return means.mean(axis=0), means.var(axis=0, ddof=1) / len(means)


def write_reference(name, spec, mean, variance, seconds, command):
    OUT.mkdir(parents=True, exist_ok=True)
    data = np.concatenate([mean, variance], axis=2).astype(np.float32)
    bitmap = mi.Bitmap(data, mi.Bitmap.PixelFormat.MultiChannel,
                       ["R", "G", "B", "variance.R", "variance.G", "variance.B"])
    bitmap.write(str(OUT / f"{name}.exr"))
    meta = {
        "scene": spec["gltf"], "environment": spec["env"], "size": list(spec["size"]),
        "renderer": f"Mitsuba {mi.__version__}", "variant": mi.variant(),
        "integrator": {"type": "path", "max_depth": spec["bounces"] + 1, "rr_depth": "none (1 << 20)",
                       "hide_emitters": False},
        "umbra_max_bounces": spec["bounces"], "microfacet": spec["microfacet"],
        "sampler": "independent", "pixel_filter": "box", "spp_per_render": spec["spp"],
        "renders": spec["renders"], "seeds": list(range(spec["renders"])),
        "channels": "R, G, B: mean of the renders' means; variance.*: their sample variance / renders",
        "plugins": "gltf_bsdf, gltf_punctual, latlong_environment (tests/reference/mitsuba_refs.py)",
        "wall_seconds": round(seconds, 1), "command": command,
    }
    (OUT / f"{name}.json").write_text(json.dumps(meta, indent=2) + "\n")


def local_bsdf(volume, roughness, base=(1, 1, 1), ior=1.5, front=True, cos_wo=0.5):
    """A glass GltfBsdf (transmission 1, metallic 0) and its hit record in the local frame, for
    the checks below: a volume boundary seen from outside (`front`) or inside, or thin-walled."""
    bsdf = mi.load_dict({"type": "gltf_bsdf"})
    bsdf.transmission, bsdf.volume, bsdf.ior, bsdf.specular = 1.0, volume, ior, 1.0
    bsdf.f0 = mi.Color3f(((ior - 1) / (ior + 1)) ** 2)
    eta_v, eta_t = (1.0, ior) if front or not volume else (ior, 1.0)
    if not volume:
        eta_v = eta_t = 1.0
    sin = float(np.sqrt(1 - cos_wo * cos_wo))
    h = dict(ng=mi.Vector3f(0, 0, 1), frame=mi.Frame3f(mi.Vector3f(0, 0, 1)), wo=mi.Vector3f(sin, 0, cos_wo),
             base=mi.Color3f(*base), metallic=mi.Float(0),
             distr=mi.MicrofacetDistribution(mi.MicrofacetType.GGX, max(roughness ** 2, 1e-4), True),
             eta_v=mi.Float(eta_v), eta_t=mi.Float(eta_t))
    return bsdf, h


def check_bsdf(count=1 << 20):
    """The transmission lobe's own checks: (1) its sampling against its density (Mitsuba's
    chi-square test, Sidak over the cases); (2) the mean sample weight against the integral of
    f |cos| by uniform sampling of the sphere (a density of 0 where f is not would show here);
    (3) the refraction BTDF against Mitsuba's own `roughdielectric` (Walter et al. 2007, GGX,
    visible normals): their ratio must be the Fresnel's (Schlick here, exact there) times
    (eta_t / eta_v)^2, the radiance compression `roughdielectric` applies and the
    KHR_materials_volume formula leaves out."""
    import mitsuba.chi2 as chi2
    cases = [(volume, front, roughness, cos_wo)
             for volume, front in ((True, True), (True, False), (False, True))
             for roughness in (0.3, 0.6) for cos_wo in (0.9, 0.5, 0.2)]
    ok = True
    for index, (volume, front, roughness, cos_wo) in enumerate(cases):
        bsdf, h = local_bsdf(volume, roughness, front=front, cos_wo=cos_wo)
        label = f"{'volume' if volume else 'thin'} {'outside' if front else 'inside'} r {roughness} cos {cos_wo}"

        def sample_func(u):
            # As `sample` does, no sample where the density is 0 (a visible normal facing away
            # from a grazing wo, rounding in Mitsuba's sampler, about 1 in 10^6).
            wi, _, _, valid = bsdf.sample_direction(h, u.x, mi.Point2f(u.y, u.z))
            return wi, dr.select(valid & (bsdf.density(h, wi) > 0), 1.0, 0.0)

        test = chi2.ChiSquareTest(chi2.SphericalDomain(), sample_func, lambda wi: bsdf.density(h, wi),
                                  sample_dim=3, sample_count=count, res=101, ires=16, seed=index)
        passed = test.run(0.01, test_count=len(cases))
        ok &= passed
        # (2) E[f cos / pdf] against E_uniform[4 pi f cos].
        rng = np.random.default_rng(index)
        u = [mi.Float(rng.random(count).astype(np.float32)) for _ in range(5)]
        wi, _, _, valid = bsdf.sample_direction(h, u[0], mi.Point2f(u[1], u[2]))
        pdf = bsdf.density(h, wi)
        weight = np.array(dr.select(valid & (pdf > 0), bsdf.bsdf(h, wi).x / pdf, 0))
        wu = mi.warp.square_to_uniform_sphere(mi.Point2f(u[3], u[4]))
        uniform = np.array(bsdf.bsdf(h, wu).x) * 4 * np.pi
        d = weight.mean() - uniform.mean()
        z = d / np.sqrt(weight.var() / count + uniform.var() / count)
        ok &= abs(z) < 4
        line = (f"{label}: chi2 p {test.p_value:.3f}; albedo by sampling {weight.mean():.4f}, "
                f"by uniform directions {uniform.mean():.4f} (z {z:+.2f})")
        if volume:
            # (3) against roughdielectric, transmission only (wi below), base colour white.
            rd = mi.load_dict({"type": "roughdielectric", "distribution": "ggx", "alpha": max(roughness ** 2, 1e-4),
                               "int_ior": 1.5, "ext_ior": 1.0, "sample_visible": True})
            si = dr.zeros(mi.SurfaceInteraction3f)
            sign = 1 if front else -1  # roughdielectric's interior lies below its normal
            wo = h["wo"]
            si.wi = mi.Vector3f(wo.x, wo.y, sign * wo.z)
            si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
            wl = mi.warp.square_to_uniform_sphere(mi.Point2f(u[3], u[4]))
            wl = mi.Vector3f(wl.x, wl.y, -dr.abs(wl.z))
            ours = np.array(bsdf.bsdf(h, wl).x)
            theirs = np.array(rd.eval(mi.BSDFContext(), si, mi.Vector3f(wl.x, wl.y, sign * wl.z)).x)
            m = bsdf.transmission_half(h, wl)
            c = dr.abs(dr.dot(wo, m))
            schlick = np.array(bsdf.dielectric_fresnel(h, c).x)
            exact = np.array(mi.fresnel(c, h["eta_t"] / h["eta_v"])[0])
            # Away from the critical angle (where float32 rounding of the cosine decides total
            # internal reflection and moves a Fresnel of almost 1 by percents): both vanish on the
            # same directions, and their ratio is the Fresnel's times eta^2.
            ratio_eta = np.array(h["eta_t"] / h["eta_v"])
            critical = np.sqrt(max(1 - ratio_eta ** 2, 0))
            away = np.abs(np.array(c) - critical) > 1e-3
            support = np.count_nonzero(((theirs > 0) != (ours > 0)) & away)
            use = (theirs > 0) & (ours > 0) & away
            ratio = ours[use] / theirs[use] / ((1 - schlick[use]) / (1 - exact[use]) * ratio_eta ** 2)
            worst = np.max(np.abs(ratio - 1))
            ok &= worst < 1e-3 and support == 0
            line += (f"; against roughdielectric: {use.sum()} directions, worst |ratio / (Fresnel ratio "
                     f"x eta^2) - 1| {worst:.1e}, one of them 0 at {support}")
        print(line, flush=True)
    print("all checks passed" if ok else "A CHECK FAILED")


def compare_variant(name, spec, work, variant):
    """The scene with the specification's lobe and with `variant` (VARIANTS), the same seeds, so
    that the difference carries little noise: the image means' relative difference, and the
    difference's z against its own spread over the renders."""
    quick = dict(spec, spp=256, renders=8)
    images = []
    for variants in (set(), {variant}):
        VARIANTS.clear()
        VARIANTS.update(variants)
        scene = mitsuba_scene(quick, work)
        images.append(np.stack([np.array(mi.render(scene, spp=quick["spp"], seed=k), dtype=np.float64)[:, :, :3]
                                for k in range(quick["renders"])]))
    VARIANTS.clear()
    base, other = images
    per_render = (other - base).mean(axis=(1, 2))  # image-mean difference per render, per channel
    d, sd = per_render.mean(axis=0), per_render.std(axis=0, ddof=1) / np.sqrt(len(per_render))
    pixel = np.abs(other.mean(axis=0) - base.mean(axis=0)) / np.maximum(base.mean(axis=0), 1e-3)
    worst = np.unravel_index(np.argmax(pixel), pixel.shape)
    print(f"{name}, {variant}: image mean {base.mean(axis=(0, 1, 2))} -> relative difference "
          f"{d / base.mean(axis=(0, 1, 2))} (z {d / np.maximum(sd, 1e-30)}); per pixel channel "
          f"median {np.median(pixel):.2e}, beyond 1 %: {np.count_nonzero(pixel > 0.01)}, largest "
          f"{pixel.max():.2e} at (x {worst[1]}, y {worst[0]}): {base.mean(axis=0)[worst]:.4f} -> "
          f"{other.mean(axis=0)[worst]:.4f}", flush=True)


def check_envmap(name, spec, work):
    """The custom environment against Mitsuba's own `envmap` (bilinear, to_world half turn):
    the relative difference of the image means and the mean squared z of the pixels."""
    quick = dict(spec, spp=256, renders=8)
    (m1, v1), (m2, v2) = (render(mitsuba_scene(quick, work, builtin), quick) for builtin in (False, True))
    z2 = (m1 - m2) ** 2 / np.maximum(v1 + v2, 1e-30)
    print(f"{name}: image mean custom {m1.mean(axis=(0, 1))}, builtin envmap {m2.mean(axis=(0, 1))}, "
          f"relative difference {(m2.mean() - m1.mean()) / m1.mean():+.4f}; mean z^2 {z2.mean():.2f}, "
          f"|z| > 3.29: {np.mean(z2 > 3.29 ** 2):.4f}")


def self_check(name, spec, work, trials=3):
    """The test's block statistic (tests/mitsuba_reference.rs), Mitsuba against itself: 128
    renders of 8 spp (1,024 spp like umbra's, variance from the 128 means) against a 32 x 1,024-spp
    reference, with and without the variance floor (the reference's per-sample variance / 1,024)."""
    scene = mitsuba_scene(spec, work)
    ref, ref_var = render(scene, dict(spec, spp=1024, renders=32))
    for trial in range(trials):
        means = np.stack([np.array(mi.render(scene, spp=8, seed=1000 + 128 * trial + k), dtype=np.float64)[:, :, :3]
                          for k in range(128)])
        mean, own = means.mean(axis=0), means.var(axis=0, ddof=1) / 128
        h, w = mean.shape[:2]
        blocks = lambda a: a[:h // 4 * 4, :w // 4 * 4].reshape(h // 4, 4, w // 4, 4, 3).sum(axis=(1, 3))  # noqa: E731
        rounding = (1e-5 * np.maximum(abs(mean), abs(ref))) ** 2
        d = blocks(mean - ref)
        for label, var in (("own variance", own), ("with the floor", np.maximum(own, ref_var * 32))):
            chi2 = np.sum(d ** 2 / blocks(var + ref_var + rounding))
            print(f"{name} trial {trial}, {label}: blocks chi2 / dof {chi2 / d.size:.3f} "
                  f"(dof {d.size}, sd {np.sqrt(2 / d.size):.3f})", flush=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scenes", nargs="*", help=f"of {', '.join(SCENES)} (default: all)")
    parser.add_argument("--check-envmap", action="store_true",
                        help="compare the custom environment with Mitsuba's envmap instead of writing references")
    parser.add_argument("--compare-variant", choices=["radiance-eta", "thin-literal-chi"],
                        help="measure what an alternative transmission lobe changes instead of writing references")
    parser.add_argument("--check-bsdf", action="store_true",
                        help="check the transmission lobe's sampling, albedo and refraction BTDF, then exit")
    parser.add_argument("--self-check", action="store_true",
                        help="the test's block statistic, Mitsuba against itself, instead of writing references")
    args = parser.parse_args()
    if args.check_bsdf:
        check_bsdf()
        return
    for name in args.scenes or list(SCENES):
        spec = SCENES[name]
        with tempfile.TemporaryDirectory() as work:
            if args.check_envmap:
                check_envmap(name, spec, Path(work))
                continue
            if args.compare_variant:
                compare_variant(name, spec, Path(work), args.compare_variant)
                continue
            if args.self_check:
                self_check(name, spec, Path(work))
                continue
            scene = mitsuba_scene(spec, Path(work))
            started = time.perf_counter()
            mean, variance = render(scene, spec)
            seconds = time.perf_counter() - started
        command = f"nice -n 10 python3 tests/reference/mitsuba_refs.py {name}"
        write_reference(name, spec, mean, variance, seconds, command)
        print(f"{name}: {spec['size'][0]}x{spec['size'][1]}, {spec['renders']} x {spec['spp']} spp in {seconds:.1f} s; "
              f"image mean {mean.mean(axis=(0, 1))}, mean relative std of the mean "
              f"{np.mean(np.sqrt(variance) / np.maximum(mean, 1e-3)):.4f}", flush=True)


if __name__ == "__main__":
    main()
