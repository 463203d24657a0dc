//! Probe bakes on disk: a baked [`ProbeVolume`] saved to a file and loaded back for the scene it
//! was baked for (`umbra bake SCENE -o FILE`, then `umbra render --mode hybrid --probes FILE`).
//!
//! A bake is valid for one scene under one environment. The file records the scene's hash
//! ([`scene_hash`]: its content, and the environment map's when there is one) and the
//! environment radiance it was baked under (the lighting's constant colour, or the map's
//! multiplier); [`load_probes`] refuses a file whose hash or environment differ from the ones
//! asked for, and any file that is not a complete bake, with an [`Error::Bake`] naming the file
//! and the problem. A checksum over the whole file tells damage ("corrupt") from a bake of
//! another scene. Nothing in a file can make it panic or allocate more than the file's size.
//!
//! # Format, version 2
//!
//! Little-endian throughout; `f32` is IEEE 754 binary32, bit for bit as the GPU held it. A
//! 96-byte header:
//!
//! | offset | type       | field |
//! |-------:|------------|-------|
//! | 0      | `[u8; 8]`  | magic, the ASCII bytes `UMBRAPRB` |
//! | 8      | `u32`      | format version: 2 |
//! | 12     | `u64`      | scene hash ([`scene_hash`]) |
//! | 20     | `[f32; 3]` | grid origin: position of probe (0, 0, 0) ([`ProbeGrid::origin`]) |
//! | 32     | `[f32; 3]` | grid spacing per axis ([`ProbeGrid::spacing`]) |
//! | 44     | `[u32; 3]` | probes per axis ([`ProbeGrid::counts`]), each at least 1, the product N at most [`ProbeSettings::MAX_PROBES`] |
//! | 56     | `u32`      | rays per probe and update ([`ProbeSettings::rays`]) |
//! | 60     | `u32`      | Chebyshev visibility: 0 off, 1 on ([`ProbeSettings::visibility`]) |
//! | 64     | `f32`      | normal bias, a fraction of the smallest spacing ([`ProbeSettings::normal_bias`]) |
//! | 68     | `f32`      | view bias, likewise ([`ProbeSettings::view_bias`]) |
//! | 72     | `u32`      | bounce sweeps of the bake ([`ProbeSettings::bounces`]) |
//! | 76     | `u32`      | averaging sweeps of the bake ([`ProbeSettings::sweeps`]) |
//! | 80     | `f32`      | hysteresis of later updates ([`ProbeSettings::hysteresis`]) |
//! | 84     | `[f32; 3]` | environment radiance the bake was made under (linear RGB) |
//!
//! then N probes' data, probe i at grid cell (i mod nx, (i / nx) mod ny, i / (nx·ny)), in three
//! arrays:
//!
//! | offset                 | type                                   | field |
//! |------------------------|----------------------------------------|-------|
//! | 96                     | `[u32; 4]` × N                         | states ([`ProbeVolume::read_states`]): flags (bit 0 active), updates since replaced, back-face hits, unused |
//! | 96 + 16 N              | `[f32; 4]` × [`IRRADIANCE_MAP_TEXELS`] × N | octahedral irradiance maps with their borders (rgb, a unused) |
//! | 96 + 16 N (1 + 64)     | `[f32; 4]` × [`DISTANCE_MAP_TEXELS`] × N   | octahedral distance maps with their borders (mean, mean square, unused ×2) |
//!
//! and last, at 96 + N × [`PROBE_BYTES`], a `u32`: the CRC-32 (IEEE 802.3, as zlib and PNG
//! compute it) of every byte before it. The file is exactly 96 + N × [`PROBE_BYTES`] + 4 bytes
//! long. The settings' spacing is not stored (it only places a new grid): a loaded volume's is
//! the grid's smallest spacing. A reader of another version refuses the file rather than guess
//! (version 1 was the same without the checksum).

use crate::environment::EnvironmentMap;
use crate::error::{Error, Result};
use crate::passes::probes::{
    ProbeGrid, ProbeSettings, ProbeVolume, DISTANCE_MAP_TEXELS, IRRADIANCE_MAP_TEXELS,
};
use crate::scene::{ContentHasher, Scene};
use crate::vk::Context;
use std::path::Path;

/// The first eight bytes of every bake.
pub const MAGIC: [u8; 8] = *b"UMBRAPRB";
/// The format version this umbra writes and reads.
pub const VERSION: u32 = 2;
/// Bytes before the probes' data.
pub const HEADER_BYTES: usize = 96;
/// Bytes of the checksum after the probes' data.
pub const CHECKSUM_BYTES: usize = 4;
/// Bytes of one probe's state and maps.
pub const PROBE_BYTES: usize = 16 * (1 + IRRADIANCE_MAP_TEXELS as usize + DISTANCE_MAP_TEXELS as usize);

/// The hash a bake of `scene` lit by `environment` (a map, or `None` for a constant colour)
/// records: [`Scene::content_hash`], combined with [`EnvironmentMap::content_hash`] when there
/// is a map. The environment's radiance multiplier is recorded apart.
pub fn scene_hash(scene: &Scene, environment: Option<&EnvironmentMap>) -> u64 {
    let scene = scene.content_hash();
    match environment {
        None => scene,
        Some(map) => {
            let mut h = ContentHasher::new();
            h.u64(scene);
            h.u64(map.content_hash());
            h.finish()
        }
    }
}

/// A bake on the CPU: everything a file holds, read from or written to it by
/// [`ProbeBake::from_bytes`] and [`ProbeBake::to_bytes`].
#[derive(Clone, Debug, PartialEq)]
pub struct ProbeBake {
    /// The hash of the scene it was baked for ([`scene_hash`]).
    pub scene_hash: u64,
    /// Where the probes are.
    pub grid: ProbeGrid,
    /// The settings it was baked with (the spacing: the grid's smallest).
    pub settings: ProbeSettings,
    /// The environment radiance it was baked under.
    pub environment: [f32; 3],
    /// Each probe's state (as [`ProbeVolume::read_states`]).
    pub states: Vec<[u32; 4]>,
    /// The irradiance maps, [`IRRADIANCE_MAP_TEXELS`] per probe.
    pub irradiance: Vec<[f32; 4]>,
    /// The distance maps, [`DISTANCE_MAP_TEXELS`] per probe.
    pub distance: Vec<[f32; 4]>,
}

impl ProbeBake {
    /// Reads `volume` back from the GPU, baked for the scene of hash `scene_hash` under
    /// `environment`.
    pub fn read(ctx: &Context, volume: &ProbeVolume, scene_hash: u64, environment: [f32; 3]) -> Result<Self> {
        Ok(Self {
            scene_hash,
            grid: volume.grid,
            settings: volume.settings,
            environment,
            states: volume.read_states(ctx)?,
            irradiance: volume.read_irradiance(ctx)?,
            distance: volume.read_distance(ctx)?,
        })
    }

    /// Uploads the bake as a probe volume, ready to light hybrid frames (or to be updated
    /// further).
    pub fn upload(&self, ctx: &Context) -> Result<ProbeVolume> {
        self.settings.validate()?;
        ProbeVolume::from_maps(ctx, self.grid, &self.settings, &self.states, &self.irradiance, &self.distance)
    }

    /// The file's bytes (the format in the [module documentation](self)).
    pub fn to_bytes(&self) -> Vec<u8> {
        let count = self.states.len();
        let mut out = Vec::with_capacity(HEADER_BYTES + count * PROBE_BYTES + CHECKSUM_BYTES);
        let u32s = |out: &mut Vec<u8>, v: &[u32]| v.iter().for_each(|x| out.extend(x.to_le_bytes()));
        let f32s = |out: &mut Vec<u8>, v: &[f32]| v.iter().for_each(|x| out.extend(x.to_le_bytes()));
        let s = &self.settings;
        out.extend(MAGIC);
        u32s(&mut out, &[VERSION]);
        out.extend(self.scene_hash.to_le_bytes());
        f32s(&mut out, &self.grid.origin);
        f32s(&mut out, &self.grid.spacing);
        u32s(&mut out, &self.grid.counts);
        u32s(&mut out, &[s.rays, s.visibility as u32]);
        f32s(&mut out, &[s.normal_bias, s.view_bias]);
        u32s(&mut out, &[s.bounces, s.sweeps]);
        f32s(&mut out, &[s.hysteresis]);
        f32s(&mut out, &self.environment);
        debug_assert_eq!(out.len(), HEADER_BYTES);
        u32s(&mut out, self.states.as_flattened());
        f32s(&mut out, self.irradiance.as_flattened());
        f32s(&mut out, self.distance.as_flattened());
        let checksum = crc32fast::hash(&out);
        out.extend(checksum.to_le_bytes());
        out
    }

    /// Parses a file's bytes; `path` names it in errors. Checks that the bytes are a whole bake
    /// of this format version with a valid grid and settings, not which scene it is for
    /// ([`ProbeBake::check`]).
    pub fn from_bytes(path: &Path, bytes: &[u8]) -> Result<Self> {
        let bad = |message: String| Error::Bake { path: path.to_path_buf(), message };
        if !bytes.starts_with(&MAGIC) {
            return Err(bad(if MAGIC.starts_with(bytes) {
                format!("truncated: {} bytes, not even the magic number", bytes.len())
            } else {
                "not a probe bake: the file does not start with UMBRAPRB (make one with `umbra bake`)".into()
            }));
        }
        let mut r = Reader { bytes, at: MAGIC.len() };
        let header = |r: &mut Reader| -> Option<_> {
            let version = r.u32()?;
            if version != VERSION {
                return Some(Err(version));
            }
            let scene_hash = r.u64()?;
            let origin = r.f32s::<3>()?;
            let spacing = r.f32s::<3>()?;
            let counts = r.u32s::<3>()?;
            let [rays, visibility] = r.u32s::<2>()?;
            let [normal_bias, view_bias] = r.f32s::<2>()?;
            let [bounces, sweeps] = r.u32s::<2>()?;
            let [hysteresis] = r.f32s::<1>()?;
            let environment = r.f32s::<3>()?;
            let settings = (rays, visibility, normal_bias, view_bias, bounces, sweeps, hysteresis);
            Some(Ok((scene_hash, ProbeGrid { origin, spacing, counts }, settings, environment)))
        };
        let truncated =
            || bad(format!("truncated: {} bytes, shorter than the {HEADER_BYTES}-byte header", bytes.len()));
        let (scene_hash, grid, settings, environment) = match header(&mut r) {
            None => return Err(truncated()),
            Some(Err(version)) => {
                return Err(bad(format!(
                    "probe bake format version {version}; this umbra reads version {VERSION}: bake again"
                )))
            }
            Some(Ok(header)) => header,
        };
        let count: u64 = grid.counts.iter().map(|&n| n as u64).product();
        // The checksum first: damage anywhere is "corrupt", whatever field it lands in.
        let expected = (count <= ProbeSettings::MAX_PROBES as u64)
            .then(|| HEADER_BYTES + count as usize * PROBE_BYTES + CHECKSUM_BYTES);
        let (body, stored) = bytes.split_at(bytes.len().max(HEADER_BYTES + CHECKSUM_BYTES) - CHECKSUM_BYTES);
        let computed = crc32fast::hash(body);
        if stored.len() != CHECKSUM_BYTES || u32::from_le_bytes(stored.try_into().unwrap()) != computed {
            return Err(bad(match expected {
                Some(expected) if bytes.len() != expected => format!(
                    "{} or corrupt: {} bytes, but a bake of {count} probes ({:?}) is {expected}, and the \
                     checksum does not match: bake again",
                    if bytes.len() < expected { "truncated" } else { "trailing data" },
                    bytes.len(),
                    grid.counts
                ),
                _ => format!(
                    "corrupt: the checksum does not match (stored {:08x}, computed {computed:08x}): the \
                     file was damaged after it was written; bake again",
                    u32::from_le_bytes(stored.try_into().unwrap_or([0; 4]))
                ),
            }));
        }
        let (rays, visibility, normal_bias, view_bias, bounces, sweeps, hysteresis) = settings;
        if !(grid.origin.iter().all(|v| v.is_finite())
            && grid.spacing.iter().all(|s| s.is_finite() && *s > 0.0))
        {
            return Err(bad(format!(
                "a grid at {:?} with spacing {:?}: damaged (not finite, or a spacing not above 0)",
                grid.origin, grid.spacing
            )));
        }
        if count == 0 || count > ProbeSettings::MAX_PROBES as u64 {
            return Err(bad(format!(
                "a grid of {:?} probes: damaged (1 to {} probes in all)",
                grid.counts,
                ProbeSettings::MAX_PROBES
            )));
        }
        if visibility > 1 {
            return Err(bad(format!("visibility flag {visibility}: damaged (0 or 1)")));
        }
        if !environment.iter().all(|v| v.is_finite() && *v >= 0.0) {
            return Err(bad(format!("environment radiance {environment:?}: damaged (finite, at least 0)")));
        }
        let settings = ProbeSettings {
            spacing: Some(grid.spacing.iter().copied().fold(f32::INFINITY, f32::min)),
            rays,
            visibility: visibility == 1,
            normal_bias,
            view_bias,
            bounces,
            sweeps,
            hysteresis,
        };
        settings.validate().map_err(|e| bad(format!("damaged settings: {e}")))?;
        let count = count as usize;
        let expected = HEADER_BYTES + count * PROBE_BYTES + CHECKSUM_BYTES;
        if bytes.len() != expected {
            let problem = if bytes.len() < expected { "truncated" } else { "trailing data" };
            return Err(bad(format!(
                "{problem}: {} bytes, but a bake of {count} probes ({:?}) is {expected}",
                bytes.len(),
                grid.counts
            )));
        }
        let data = &bytes[HEADER_BYTES..];
        let words = |from: usize, n: usize| {
            data[from..from + 16 * n]
                .chunks_exact(4)
                .map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]))
                .collect::<Vec<u32>>()
        };
        let quads = |w: Vec<u32>| w.chunks_exact(4).map(|q| [q[0], q[1], q[2], q[3]]).collect::<Vec<_>>();
        let floats = |q: Vec<[u32; 4]>| q.into_iter().map(|q| q.map(f32::from_bits)).collect::<Vec<_>>();
        let irradiance_texels = count * IRRADIANCE_MAP_TEXELS as usize;
        let distance_texels = count * DISTANCE_MAP_TEXELS as usize;
        Ok(Self {
            scene_hash,
            grid,
            settings,
            environment,
            states: quads(words(0, count)),
            irradiance: floats(quads(words(16 * count, irradiance_texels))),
            distance: floats(quads(words(16 * (count + irradiance_texels), distance_texels))),
        })
    }

    /// Checks that the bake is for the scene of hash `scene_hash` ([`scene_hash`]) lit by
    /// `environment`; `path` names the file in the error.
    pub fn check(&self, path: &Path, scene_hash: u64, environment: [f32; 3]) -> Result<()> {
        let bad = |message: String| Err(Error::Bake { path: path.to_path_buf(), message });
        if self.scene_hash != scene_hash {
            return bad(format!(
                "baked for another scene (hash {:016x}), this scene is {scene_hash:016x}: bake again",
                self.scene_hash
            ));
        }
        if self.environment != environment {
            return bad(format!(
                "baked under environment radiance {:?}, this render's is {environment:?}: bake again \
                 under this environment",
                self.environment
            ));
        }
        Ok(())
    }
}

/// Little-endian values from the front of a byte slice; `None` past its end.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take<const N: usize>(&mut self) -> Option<[u8; N]> {
        let v = self.bytes.get(self.at..self.at + N)?.try_into().ok()?;
        self.at += N;
        Some(v)
    }
    fn u32(&mut self) -> Option<u32> {
        self.take().map(u32::from_le_bytes)
    }
    fn u64(&mut self) -> Option<u64> {
        self.take().map(u64::from_le_bytes)
    }
    fn u32s<const N: usize>(&mut self) -> Option<[u32; N]> {
        let mut v = [0; N];
        for x in &mut v {
            *x = self.u32()?;
        }
        Some(v)
    }
    fn f32s<const N: usize>(&mut self) -> Option<[f32; N]> {
        self.u32s::<N>().map(|v| v.map(f32::from_bits))
    }
}

/// Saves `volume` (read back from the GPU), baked for the scene of hash `scene_hash`
/// ([`scene_hash`]) under `environment` (the lighting's
/// [`crate::passes::deferred::LightingSettings::env`]), to `path`.
pub fn save_probes(
    ctx: &Context,
    path: &Path,
    volume: &ProbeVolume,
    scene_hash: u64,
    environment: [f32; 3],
) -> Result<()> {
    let bytes = ProbeBake::read(ctx, volume, scene_hash, environment)?.to_bytes();
    crate::atomic::write(path, &bytes)
}

/// Loads the bake at `path` onto the GPU, after checking that it is a whole bake made for the
/// scene of hash `scene_hash` ([`scene_hash`]) under `environment` (the lighting's
/// [`crate::passes::deferred::LightingSettings::env`]).
pub fn load_probes(
    ctx: &Context,
    path: &Path,
    scene_hash: u64,
    environment: [f32; 3],
) -> Result<ProbeVolume> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let bake = ProbeBake::from_bytes(path, &bytes)?;
    bake.check(path, scene_hash, environment)?;
    bake.upload(ctx)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bake() -> ProbeBake {
        let grid = ProbeGrid { origin: [-1.0, 0.5, 2.0], spacing: [0.25; 3], counts: [3, 2, 2] };
        let n = grid.count() as usize;
        let settings =
            ProbeSettings { spacing: Some(0.25), rays: 64, bounces: 2, sweeps: 3, ..Default::default() };
        let texel = |i: usize| [i as f32 * 0.5, -(i as f32), f32::MIN_POSITIVE, 1e30];
        ProbeBake {
            scene_hash: 0x0123_4567_89ab_cdef,
            grid,
            settings,
            environment: [0.1, 0.2, 0.3],
            states: (0..n as u32).map(|i| [i & 1, i, 7 * i, 0]).collect(),
            irradiance: (0..n * IRRADIANCE_MAP_TEXELS as usize).map(texel).collect(),
            distance: (0..n * DISTANCE_MAP_TEXELS as usize).map(|i| texel(i + 1)).collect(),
        }
    }

    fn error(bytes: &[u8]) -> String {
        match ProbeBake::from_bytes(Path::new("dir/probes.bake"), bytes) {
            Ok(_) => panic!("{} bytes accepted", bytes.len()),
            Err(e @ Error::Bake { .. }) => {
                let message = e.to_string();
                assert!(message.starts_with("dir/probes.bake: "), "{message}");
                message
            }
            Err(e) => panic!("not a bake error: {e}"),
        }
    }

    #[test]
    fn bytes_round_trip_bit_for_bit() {
        let b = bake();
        let bytes = b.to_bytes();
        assert_eq!(bytes.len(), HEADER_BYTES + 12 * PROBE_BYTES + CHECKSUM_BYTES);
        assert_eq!(&bytes[..8], b"UMBRAPRB");
        assert_eq!(bytes[8..12], 2u32.to_le_bytes());
        let (body, checksum) = bytes.split_at(bytes.len() - 4);
        assert_eq!(checksum, crc32fast::hash(body).to_le_bytes(), "the CRC-32 of all before it, last");
        assert_eq!(bytes[12..20], 0x0123_4567_89ab_cdefu64.to_le_bytes());
        assert_eq!(bytes[44..48], 3u32.to_le_bytes(), "counts at offset 44");
        assert_eq!(bytes[84..88], 0.1f32.to_le_bytes(), "environment at offset 84");
        let back = ProbeBake::from_bytes(Path::new("x"), &bytes).unwrap();
        assert_eq!(back, b);
        assert_eq!(back.to_bytes(), bytes);
    }

    #[test]
    fn every_truncation_is_refused() {
        let bytes = bake().to_bytes();
        for len in 0..bytes.len() {
            let message = error(&bytes[..len]);
            assert!(message.contains("truncated"), "{len} bytes: {message}");
        }
        let mut longer = bytes.clone();
        longer.push(0);
        assert!(error(&longer).contains("trailing data"));
    }

    #[test]
    fn a_bad_magic_a_new_version_and_damage_are_named() {
        let bytes = bake().to_bytes();
        assert!(error(b"").contains("truncated"));
        assert!(error(b"glTF\x02\0\0\0").contains("not a probe bake"));
        let mut other = bytes.clone();
        other[..8].copy_from_slice(b"UMBRAPRC");
        assert!(error(&other).contains("does not start with UMBRAPRB"));
        let mut newer = bytes.clone();
        newer[8..12].copy_from_slice(&3u32.to_le_bytes());
        assert!(error(&newer).contains("version 3; this umbra reads version 2"));
        let mut older = bytes.clone();
        older[8..12].copy_from_slice(&1u32.to_le_bytes());
        assert!(error(&older).contains("version 1; this umbra reads version 2: bake again"));
        // A field patched and the checksum sealed again, as a wrong writer would: each field's
        // own check names it.
        let patch = |offset: usize, value: [u8; 4]| {
            let mut b = bytes.clone();
            b[offset..offset + 4].copy_from_slice(&value);
            let n = b.len() - CHECKSUM_BYTES;
            let checksum = crc32fast::hash(&b[..n]);
            b[n..].copy_from_slice(&checksum.to_le_bytes());
            error(&b)
        };
        // Counts whose product overflows u32 and sizes that would allocate terabytes: refused
        // before any allocation.
        assert!(patch(44, u32::MAX.to_le_bytes()).contains("probes in all"));
        assert!(patch(48, 0u32.to_le_bytes()).contains("probes in all"));
        assert!(patch(32, f32::NAN.to_le_bytes()).contains("spacing"));
        assert!(patch(56, 65u32.to_le_bytes()).contains("65 rays"));
        assert!(patch(60, 2u32.to_le_bytes()).contains("visibility"));
        assert!(patch(88, (-1.0f32).to_le_bytes()).contains("environment"));
        // A grid of more probes than the file holds.
        assert!(patch(44, 4u32.to_le_bytes()).contains("truncated"));
    }

    /// One flipped bit anywhere past the magic and version is "corrupt" (in the counts, whose
    /// file length then disagrees, "truncated or corrupt" / "trailing data or corrupt"), never
    /// a bake of another scene, a damaged field or a bake that loads.
    #[test]
    fn every_flipped_bit_is_corrupt() {
        let bytes = bake().to_bytes();
        for offset in 12..bytes.len() {
            for bit in [0, 3, 7] {
                let mut b = bytes.clone();
                b[offset] ^= 1 << bit;
                let message = error(&b);
                assert!(message.contains("corrupt"), "byte {offset} bit {bit}: {message}");
            }
        }
    }

    #[test]
    fn another_scene_or_environment_is_refused() {
        let b = bake();
        let path = Path::new("probes.bake");
        b.check(path, b.scene_hash, b.environment).unwrap();
        let message = b.check(path, 42, b.environment).unwrap_err().to_string();
        assert_eq!(
            message,
            "probes.bake: baked for another scene (hash 0123456789abcdef), this scene is \
             000000000000002a: bake again"
        );
        let message = b.check(path, b.scene_hash, [0.0; 3]).unwrap_err().to_string();
        assert!(message.contains("environment radiance [0.1, 0.2, 0.3]"), "{message}");
    }
}
