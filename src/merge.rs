//! One path-traced render split across processes or machines, and joined again.
//!
//! `umbra render --sample-range A..B` traces exactly samples `A..B` of the counter-based
//! sequence (a render from 0 draws the same numbers for them) and `--tile X,Y,W,H` exactly the
//! pixels of one region of the image (their rays and random numbers those of the whole image).
//! Each part's EXR ([`PathExr`]) keeps the running mean and second moment with the sample ranges,
//! the region and an identity of the render in its header; [`merge`] weighs the parts' means
//! and moments by their sample counts and places the regions, which gives the render one process
//! would have made (equal to float rounding: the parts' sums round in another order).
//!
//! Each part also records the whole render's plan: the image (`image`) and the samples per pixel
//! of the whole render (`spp`). [`merge`] refuses a merge that leaves any of the plan out (a
//! lost array task: samples 48..64 missing, or the top tile), naming what is missing;
//! [`merge_partial`] joins what there is and says what is missing, for a merge that asks for
//! exactly that (`umbra merge --allow-partial`).

use crate::error::{Error, Result};
use crate::output::{read_exr, write_exr_with, Layer};
use crate::passes::pathtrace::PathSettings;
use crate::render::{LobeSplitImage, PathImage};
use std::ops::Range;
use std::path::{Path, PathBuf};

/// A rectangle of pixels: its top-left pixel and its width and height.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Region {
    /// Left column, top row.
    pub origin: (u32, u32),
    /// Width and height.
    pub size: (u32, u32),
}

/// "the 15x30 pixels from (25, 0)".
impl std::fmt::Display for Region {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "the {}x{} pixels from ({}, {})", self.size.0, self.size.1, self.origin.0, self.origin.1)
    }
}

impl Region {
    fn area(&self) -> u64 {
        self.size.0 as u64 * self.size.1 as u64
    }

    fn end(&self) -> (u32, u32) {
        (self.origin.0 + self.size.0, self.origin.1 + self.size.1)
    }

    fn overlaps(&self, other: &Region) -> bool {
        let (a, b) = (self.end(), other.end());
        self.origin.0 < b.0 && other.origin.0 < a.0 && self.origin.1 < b.1 && other.origin.1 < a.1
    }
}

/// A path-traced render (or part of one) as its EXR holds it: the main RGB layer the mean, the
/// layers `moment` (mean of the squared samples), `variance` (of the mean), `albedo` and
/// `emission` (the first hit's, means over the samples), `normal` and `depth` (the first hit of
/// the first sample), with `--denoise` the main layer denoised and the mean as `noisy` and the
/// lobe split's layers `specular` and `split` (RGBA: [`LobeSplitImage`]'s means, which a merge
/// weighs by sample counts as the mean, so the merged render denoises as one render), and one
/// header attribute, `umbra.part`, of five lines: `samples A..B[,C..D…]` (the sample ranges),
/// `spp N` (the whole render's samples per pixel, 0..N), `image WxH` (the whole image), `region
/// X,Y,WxH` and `render …` (what must agree between parts: scene, lighting, camera and every
/// setting but the samples and the region). One attribute, so that the header's bytes do not
/// depend on the order a hash map lists several in. A file without the `spp` line (from an umbra
/// before it) merges only partially.
#[derive(Debug, Clone, PartialEq)]
pub struct PathExr {
    /// Width and height of the whole image.
    pub image: (u32, u32),
    /// The pixels this part holds.
    pub region: Region,
    /// Its samples of the sequence, sorted, disjoint and not touching.
    pub samples: Vec<Range<u32>>,
    /// The whole render's samples per pixel (samples `0..N`, of which the parts hold some);
    /// `None` in a file written before parts recorded it.
    pub planned_spp: Option<u32>,
    /// The render's identity (equal in every part of one render).
    pub render: String,
    /// Mean radiance per pixel of the region, row-major.
    pub mean: Vec<[f32; 3]>,
    /// Mean of the squared samples.
    pub moment: Vec<[f32; 3]>,
    /// Base colour at the first hit, mean over the samples.
    pub albedo: Vec<[f32; 3]>,
    /// The fraction of the samples whose first hit is a surface (the albedo's alpha, channel
    /// `albedo.A`; the denoiser demodulates only where it is above 0). `None` in a file written
    /// without it: such a part merges, but the merge cannot be denoised.
    pub coverage: Option<Vec<f32>>,
    /// Shading normal at the first hit.
    pub normal: Vec<[f32; 3]>,
    /// Distance to the first hit (infinite for a miss).
    pub depth: Vec<f32>,
    /// Radiance emitted at the first hit, mean over the samples.
    pub emission: Vec<[f32; 3]>,
    /// The denoised image (`umbra render --denoise`): written as the main layer, `mean` then as
    /// layer `noisy`. Never read back: [`PathExr::read`] takes the mean from `noisy`, so a merge
    /// joins raw estimates.
    pub denoised: Option<Vec<[f32; 3]>>,
    /// The denoiser's lobe split ([`PathImage::lobe_split`]), in the parts of a `--denoise`
    /// render: layers `specular` and `split`, RGBA.
    pub lobe_split: Option<LobeSplitImage>,
}

const MAIN: [&str; 3] = ["R", "G", "B"];
/// The header attribute that describes a part ([`PathExr`]).
const PART_ATTRIBUTE: &str = "umbra.part";
const XYZ: [&str; 3] = ["X", "Y", "Z"];
const RGBA: [&str; 4] = ["R", "G", "B", "A"];

impl PathExr {
    /// The EXR of `image`, rendered with `settings`; `render` names what else identifies the
    /// render (scene, lighting, camera). Its plan ([`PathExr::planned_spp`]) is the samples up to
    /// its last: set it for a part of a render of more samples.
    pub fn new(image: &PathImage, settings: &PathSettings, render: String) -> Self {
        let rgb = |v: &Vec<[f32; 4]>| v.iter().map(|p| [p[0], p[1], p[2]]).collect();
        let (image_size, origin) = match settings.tile {
            Some(t) => (t.image, t.origin),
            None => (image.size, (0, 0)),
        };
        Self {
            image: image_size,
            region: Region { origin, size: image.size },
            samples: std::iter::once(settings.first_sample..settings.first_sample + image.spp).collect(),
            planned_spp: Some(settings.first_sample + image.spp),
            render,
            mean: rgb(&image.mean),
            moment: rgb(&image.moment),
            albedo: rgb(&image.albedo),
            coverage: Some(image.albedo.iter().map(|p| p[3]).collect()),
            normal: rgb(&image.normal_depth),
            depth: image.normal_depth.iter().map(|p| p[3]).collect(),
            emission: rgb(&image.emission),
            denoised: None,
            lobe_split: image.lobe_split.clone(),
        }
    }

    /// The render as the path tracer's image, for the denoiser: its mean with the sample count,
    /// moment, albedo with its coverage, normal and depth, emission and lobe split. An error
    /// without the coverage (a file written before it was kept).
    pub fn to_image(&self) -> Result<PathImage> {
        let coverage = self.coverage.as_ref().ok_or_else(|| {
            Error::Invalid("the render has no albedo coverage (albedo.A): re-render it to denoise it".into())
        })?;
        let spp = self.spp();
        let rgba = |v: &[[f32; 3]], a: &mut dyn FnMut(usize) -> f32| -> Vec<[f32; 4]> {
            v.iter().enumerate().map(|(i, p)| [p[0], p[1], p[2], a(i)]).collect()
        };
        Ok(PathImage {
            size: self.region.size,
            spp,
            mean: rgba(&self.mean, &mut |_| spp as f32),
            moment: rgba(&self.moment, &mut |_| 0.0),
            albedo: rgba(&self.albedo, &mut |i| coverage[i]),
            normal_depth: rgba(&self.normal, &mut |i| self.depth[i]),
            emission: rgba(&self.emission, &mut |_| 0.0),
            lobe_split: self.lobe_split.clone(),
            nonfinite_samples: 0,
            nonfinite_sources: 0,
            gpu_ms: 0.0,
            segments: 0,
            marches_exhausted: 0,
        })
    }

    /// Samples per pixel.
    pub fn spp(&self) -> u32 {
        self.samples.iter().map(|r| r.end - r.start).sum()
    }

    /// Per pixel, the estimated variance of the mean (sample variance / n).
    pub fn variance_of_mean(&self) -> Vec<[f32; 3]> {
        let n = self.spp().max(2) as f32;
        self.mean
            .iter()
            .zip(&self.moment)
            .map(|(m, s)| [0, 1, 2].map(|c| (s[c] - m[c] * m[c]).max(0.0) / (n - 1.0)))
            .collect()
    }

    /// Writes the EXR.
    pub fn write(&self, path: &Path) -> Result<()> {
        let flat = |v: &[[f32; 3]]| v.iter().flatten().copied().collect::<Vec<f32>>();
        let (mean, moment, normal) = (flat(&self.mean), flat(&self.moment), flat(&self.normal));
        let albedo: Vec<f32> = match &self.coverage {
            Some(coverage) => {
                self.albedo.iter().zip(coverage).flat_map(|(p, a)| [p[0], p[1], p[2], *a]).collect()
            }
            None => flat(&self.albedo),
        };
        let albedo_channels: &[&str] = if self.coverage.is_some() { &RGBA } else { &MAIN };
        let split = self.lobe_split.as_ref().map(|l| {
            let flat4 = |v: &[[f32; 4]]| v.iter().flatten().copied().collect::<Vec<f32>>();
            (flat4(&l.specular), flat4(&l.split))
        });
        let emission = flat(&self.emission);
        let variance = flat(&self.variance_of_mean());
        let denoised = self.denoised.as_deref().map(flat);
        let samples: Vec<String> = self.samples.iter().map(|r| format!("{}..{}", r.start, r.end)).collect();
        let r = self.region;
        write_exr_with(
            path,
            r.size.0 as usize,
            r.size.1 as usize,
            &[
                match &denoised {
                    Some(denoised) => Layer { name: "", channels: &MAIN, data: denoised },
                    None => Layer { name: "", channels: &MAIN, data: &mean },
                },
                Layer { name: "albedo", channels: albedo_channels, data: &albedo },
                Layer { name: "normal", channels: &XYZ, data: &normal },
                Layer { name: "depth", channels: &["Z"], data: &self.depth },
                Layer { name: "emission", channels: &MAIN, data: &emission },
                Layer { name: "variance", channels: &MAIN, data: &variance },
                Layer { name: "moment", channels: &MAIN, data: &moment },
            ]
            .into_iter()
            .chain(denoised.is_some().then_some(Layer { name: "noisy", channels: &MAIN, data: &mean }))
            .chain(split.iter().flat_map(|(specular, split)| {
                [
                    Layer { name: "specular", channels: &RGBA, data: specular },
                    Layer { name: "split", channels: &RGBA, data: split },
                ]
            }))
            .collect::<Vec<_>>(),
            &[(
                PART_ATTRIBUTE,
                format!(
                    "samples {}\n{}image {}x{}\nregion {},{},{}x{}\nrender {}",
                    samples.join(","),
                    self.planned_spp.map_or(String::new(), |n| format!("spp {n}\n")),
                    self.image.0,
                    self.image.1,
                    r.origin.0,
                    r.origin.1,
                    r.size.0,
                    r.size.1,
                    self.render
                ),
            )],
        )
    }

    /// Reads an EXR that [`PathExr::write`] wrote; an error naming the file and what is missing
    /// or malformed otherwise.
    pub fn read(path: &Path) -> Result<Self> {
        let exr = read_exr(path)?;
        let bad = |message: String| Error::Image { path: path.to_path_buf(), message };
        let part =
            exr.attributes.iter().find(|(k, _)| k == PART_ATTRIBUTE).map(|(_, v)| v.as_str()).ok_or_else(
                || {
                    bad(format!(
                        "no '{PART_ATTRIBUTE}' attribute: not a path-traced render written by umbra render"
                    ))
                },
            )?;
        let attribute = |name: &str| {
            part.lines()
                .find_map(|line| line.strip_prefix(name).and_then(|rest| rest.strip_prefix(' ')))
                .ok_or_else(|| bad(format!("its '{PART_ATTRIBUTE}' attribute has no '{name}' line")))
        };
        let channel = |name: &str| {
            exr.channels
                .iter()
                .find(|(n, _)| n == name)
                .map(|(_, v)| v.as_slice())
                .ok_or_else(|| bad(format!("no channel '{name}'")))
        };
        let rgb = |layer: &str, names: [&str; 3]| -> Result<Vec<[f32; 3]>> {
            let full = |c: &str| if layer.is_empty() { c.to_string() } else { format!("{layer}.{c}") };
            let [a, b, c] = [channel(&full(names[0]))?, channel(&full(names[1]))?, channel(&full(names[2]))?];
            Ok((0..a.len()).map(|i| [a[i], b[i], c[i]]).collect())
        };
        let has = |name: &str| exr.channels.iter().any(|(n, _)| n == name);
        let rgba = |layer: &str| -> Result<Vec<[f32; 4]>> {
            let [a, b, c, d] = RGBA.map(|c| channel(&format!("{layer}.{c}")));
            let [a, b, c, d] = [a?, b?, c?, d?];
            Ok((0..a.len()).map(|i| [a[i], b[i], c[i], d[i]]).collect())
        };
        let lobe_split = match (has("specular.R"), has("split.R")) {
            (true, true) => Some(LobeSplitImage { specular: rgba("specular")?, split: rgba("split")? }),
            (false, false) => None,
            _ => {
                return Err(bad(
                    "one of the lobe split's layers 'specular' and 'split' without the other".into()
                ))
            }
        };
        let image = parse_size(attribute("image")?).ok_or_else(|| bad("malformed image size".into()))?;
        let region = parse_region(attribute("region")?).ok_or_else(|| bad("malformed region".into()))?;
        let samples =
            parse_samples(attribute("samples")?).ok_or_else(|| bad("malformed sample ranges".into()))?;
        let planned_spp = match attribute("spp") {
            Ok(n) => Some(n.parse::<u32>().map_err(|_| bad(format!("malformed spp '{n}'")))?),
            Err(_) => None,
        };
        if let (Some(n), Some(last)) = (planned_spp, samples.last()) {
            if last.end > n {
                return Err(bad(format!(
                    "samples {} beyond the render's {n} samples per pixel",
                    describe(&samples)
                )));
            }
        }
        if (exr.width, exr.height) != (region.size.0 as usize, region.size.1 as usize) {
            return Err(bad(format!(
                "{}x{} pixels but its region is {}x{}",
                exr.width, exr.height, region.size.0, region.size.1
            )));
        }
        if region.end().0 > image.0 || region.end().1 > image.1 {
            return Err(bad("its region lies outside its image".into()));
        }
        Ok(Self {
            image,
            region,
            samples,
            planned_spp,
            render: attribute("render")?.to_string(),
            // A denoised render keeps its raw estimate in `noisy`: that is what merges.
            mean: if exr.channels.iter().any(|(n, _)| n == "noisy.R") {
                rgb("noisy", MAIN)?
            } else {
                rgb("", MAIN)?
            },
            moment: rgb("moment", MAIN)?,
            albedo: rgb("albedo", MAIN)?,
            coverage: if has("albedo.A") { Some(channel("albedo.A")?.to_vec()) } else { None },
            normal: rgb("normal", XYZ)?,
            depth: channel("depth.Z")?.to_vec(),
            emission: rgb("emission", MAIN)?,
            denoised: None,
            lobe_split,
        })
    }
}

fn parse_size(s: &str) -> Option<(u32, u32)> {
    let (w, h) = s.split_once('x')?;
    Some((w.parse().ok()?, h.parse().ok()?))
}

fn parse_region(s: &str) -> Option<Region> {
    let mut parts = s.splitn(3, ',');
    let x = parts.next()?.parse().ok()?;
    let y = parts.next()?.parse().ok()?;
    let size = parse_size(parts.next()?)?;
    Some(Region { origin: (x, y), size })
}

/// `A..B[,C..D…]`: ranges, each non-empty.
fn parse_samples(s: &str) -> Option<Vec<Range<u32>>> {
    s.split(',')
        .map(|r| {
            let (a, b) = r.split_once("..")?;
            let (a, b): (u32, u32) = (a.parse().ok()?, b.parse().ok()?);
            (a < b).then_some(a..b)
        })
        .collect()
}

/// The union of disjoint ranges, sorted, touching ones joined; `None` where two overlap.
fn union(ranges: impl IntoIterator<Item = Range<u32>>) -> Option<Vec<Range<u32>>> {
    let mut all: Vec<Range<u32>> = ranges.into_iter().collect();
    all.sort_by_key(|r| r.start);
    let mut out: Vec<Range<u32>> = Vec::new();
    for r in all {
        match out.last_mut() {
            Some(last) if r.start < last.end => return None,
            Some(last) if r.start == last.end => last.end = r.end,
            _ => out.push(r),
        }
    }
    Some(out)
}

fn describe(samples: &[Range<u32>]) -> String {
    samples.iter().map(|r| format!("{}..{}", r.start, r.end)).collect::<Vec<_>>().join(",")
}

/// Joins parts of one render (each with the file it came from, for the errors) into the whole
/// render ([`merge_partial`]); refused, naming the files and what is missing, unless the parts
/// hold every sample of the render's plan ([`PathExr::planned_spp`]) on every pixel of its image.
pub fn merge(parts: &[(PathBuf, PathExr)]) -> Result<PathExr> {
    let (merged, missing) = merge_partial(parts)?;
    if missing.is_empty() {
        return Ok(merged);
    }
    let names: Vec<String> = parts.iter().map(|(f, _)| f.display().to_string()).collect();
    Err(Error::Invalid(format!(
        "{} {} not the whole render: {} missing (a lost part?); render the missing parts, or merge \
         with --allow-partial to write what there is",
        names.join(", "),
        if names.len() == 1 { "is" } else { "are" },
        missing.join("; "),
    )))
}

/// [`merge`] of what there is: the joined parts, and what the render's plan holds that they do
/// not ([`PathExr::missing`], empty for a whole render).
pub fn merge_partial(parts: &[(PathBuf, PathExr)]) -> Result<(PathExr, Vec<String>)> {
    let merged = join(parts)?;
    let missing = merged.missing();
    Ok((merged, missing))
}

impl PathExr {
    /// What the render's plan holds that this render lacks, in words: sample ranges of the
    /// planned `0..N` (or that the plan is unknown), and the rows or columns of the image outside
    /// its region. Empty for a whole render.
    pub fn missing(&self) -> Vec<String> {
        let mut missing = Vec::new();
        match self.planned_spp {
            None => missing.push(
                "the render's total samples (the parts were written by an umbra that did not record \
                 them)"
                    .to_string(),
            ),
            Some(n) => {
                let mut gaps = Vec::new();
                let mut at = 0;
                for r in self.samples.iter().chain(std::iter::once(&(n..n))) {
                    if r.start > at {
                        gaps.push(format!("{at}..{}", r.start));
                    }
                    at = at.max(r.end);
                }
                if !gaps.is_empty() {
                    missing.push(format!("samples {} of the render's 0..{n}", gaps.join(", ")));
                }
            }
        }
        let (r, (w, h)) = (self.region, self.image);
        let (end_x, end_y) = r.end();
        let strips = [
            (r.origin.1 > 0, format!("rows 0..{} (above)", r.origin.1)),
            (end_y < h, format!("rows {end_y}..{h} (below)")),
            (r.origin.0 > 0, format!("columns 0..{} (left)", r.origin.0)),
            (end_x < w, format!("columns {end_x}..{w} (right)")),
        ];
        let strips: Vec<String> = strips.into_iter().filter(|s| s.0).map(|s| s.1).collect();
        if !strips.is_empty() {
            missing.push(format!(
                "pixels of the {w}x{h} image outside the parts' region ({r}): {}",
                strips.join(", ")
            ));
        }
        missing
    }
}

/// Joins parts of one render (each with the file it came from, for the errors): parts of the
/// same region and disjoint sample ranges into one of all their samples (means and second
/// moments weighted by sample counts, as are the albedo, its coverage, the emission and the lobe
/// split; the normal and depth of the part with the earliest samples), then regions into the
/// rectangle they tile. The coverage and the lobe split are kept where every part has them.
/// Refused, naming the files: parts of different renders or images, overlapping samples of one
/// region, overlapping regions, regions with different samples, regions that leave a hole in
/// their bounding rectangle.
fn join(parts: &[(PathBuf, PathExr)]) -> Result<PathExr> {
    let (first_path, first) = parts.first().ok_or_else(|| Error::Invalid("nothing to merge".into()))?;
    let invalid = |message: String| Err(Error::Invalid(message));
    for (path, part) in &parts[1..] {
        if part.render != first.render || part.image != first.image || part.planned_spp != first.planned_spp {
            let plan = |p: &PathExr| {
                format!(
                    "{}x{}, {} spp",
                    p.image.0,
                    p.image.1,
                    p.planned_spp.map_or("?".into(), |n| n.to_string())
                )
            };
            return invalid(format!(
                "{} and {} are not parts of one render:\n  {} ({})\n  {} ({})",
                first_path.display(),
                path.display(),
                first.render,
                plan(first),
                part.render,
                plan(part)
            ));
        }
    }
    // Samples first: one part per region.
    let mut regions: Vec<Region> = parts.iter().map(|(_, p)| p.region).collect();
    regions.sort();
    regions.dedup();
    let mut tiles: Vec<(PathBuf, PathExr)> = Vec::new();
    for region in regions {
        let mut group: Vec<&(PathBuf, PathExr)> = parts.iter().filter(|(_, p)| p.region == region).collect();
        group.sort_by_key(|(_, p)| p.samples[0].start);
        let Some(samples) = union(group.iter().flat_map(|(_, p)| p.samples.iter().cloned())) else {
            let names: Vec<String> =
                group.iter().map(|(f, p)| format!("{} ({})", f.display(), describe(&p.samples))).collect();
            return invalid(format!("overlapping sample ranges in one region: {}", names.join(", ")));
        };
        let total: f64 = group.iter().map(|(_, p)| p.spp() as f64).sum();
        let weighted = |field: fn(&PathExr) -> &Vec<[f32; 3]>| -> Vec<[f32; 3]> {
            let pixels = field(&group[0].1).len();
            (0..pixels)
                .map(|i| {
                    [0, 1, 2].map(|c| {
                        let sum: f64 =
                            group.iter().map(|(_, p)| p.spp() as f64 * field(p)[i][c] as f64).sum();
                        (sum / total) as f32
                    })
                })
                .collect()
        };
        // The same weighting for the layers a part may lack and any number of channels: the
        // parts' pixels, `None` where one lacks the layer.
        let spp: Vec<f64> = group.iter().map(|(_, p)| p.spp() as f64).collect();
        let weigh = |fields: Option<Vec<&[[f32; 4]]>>| -> Option<Vec<[f32; 4]>> {
            let fields = fields?;
            Some(
                (0..fields[0].len())
                    .map(|i| {
                        [0, 1, 2, 3].map(|c| {
                            let sum: f64 = spp.iter().zip(&fields).map(|(n, f)| n * f[i][c] as f64).sum();
                            (sum / total) as f32
                        })
                    })
                    .collect(),
            )
        };
        let layer = |f: fn(&PathExr) -> Option<&[[f32; 4]]>| {
            group.iter().map(|(_, p)| f(p)).collect::<Option<Vec<_>>>()
        };
        // The coverage as the first channel of 4-channel pixels (the others 0).
        let coverage: Option<Vec<Vec<[f32; 4]>>> = group
            .iter()
            .map(|(_, p)| p.coverage.as_ref().map(|c| c.iter().map(|&a| [a, 0.0, 0.0, 0.0]).collect()))
            .collect();
        let coverage = weigh(coverage.as_ref().map(|c| c.iter().map(|v| v.as_slice()).collect()))
            .map(|c| c.into_iter().map(|p| p[0]).collect());
        let lobe_split = match (
            weigh(layer(|p| p.lobe_split.as_ref().map(|l| l.specular.as_slice()))),
            weigh(layer(|p| p.lobe_split.as_ref().map(|l| l.split.as_slice()))),
        ) {
            (Some(specular), Some(split)) => Some(LobeSplitImage { specular, split }),
            _ => None,
        };
        let (path, earliest) = group[0];
        tiles.push((
            path.clone(),
            PathExr {
                samples,
                mean: weighted(|p| &p.mean),
                moment: weighted(|p| &p.moment),
                albedo: weighted(|p| &p.albedo),
                coverage,
                emission: weighted(|p| &p.emission),
                lobe_split,
                ..earliest.clone()
            },
        ));
    }
    if tiles.len() == 1 {
        return Ok(tiles.pop().expect("one tile").1);
    }
    // Then regions: disjoint, with the same samples, tiling their bounding rectangle.
    for (i, (a_path, a)) in tiles.iter().enumerate() {
        for (b_path, b) in &tiles[i + 1..] {
            if a.region.overlaps(&b.region) {
                return invalid(format!(
                    "the regions of {} and {} overlap ({} and {})",
                    a_path.display(),
                    b_path.display(),
                    a.region,
                    b.region
                ));
            }
            if a.samples != b.samples {
                return invalid(format!(
                    "regions of {} and {} have different samples ({} and {}): merge each region's samples first",
                    a_path.display(),
                    b_path.display(),
                    describe(&a.samples),
                    describe(&b.samples)
                ));
            }
        }
    }
    let x0 = tiles.iter().map(|(_, t)| t.region.origin.0).min().expect("tiles");
    let y0 = tiles.iter().map(|(_, t)| t.region.origin.1).min().expect("tiles");
    let x1 = tiles.iter().map(|(_, t)| t.region.end().0).max().expect("tiles");
    let y1 = tiles.iter().map(|(_, t)| t.region.end().1).max().expect("tiles");
    let bounds = Region { origin: (x0, y0), size: (x1 - x0, y1 - y0) };
    if tiles.iter().map(|(_, t)| t.region.area()).sum::<u64>() != bounds.area() {
        let names: Vec<String> = tiles.iter().map(|(f, _)| f.display().to_string()).collect();
        return invalid(format!(
            "the regions of {} leave holes in the rectangle they span ({bounds}): give every tile",
            names.join(", "),
        ));
    }
    let pixels = bounds.area() as usize;
    let every = |f: fn(&PathExr) -> bool| tiles.iter().all(|(_, t)| f(t));
    let mut out = PathExr {
        region: bounds,
        mean: vec![[0.0; 3]; pixels],
        moment: vec![[0.0; 3]; pixels],
        albedo: vec![[0.0; 3]; pixels],
        coverage: every(|t| t.coverage.is_some()).then(|| vec![0.0; pixels]),
        normal: vec![[0.0; 3]; pixels],
        depth: vec![0.0; pixels],
        emission: vec![[0.0; 3]; pixels],
        lobe_split: every(|t| t.lobe_split.is_some())
            .then(|| LobeSplitImage { specular: vec![[0.0; 4]; pixels], split: vec![[0.0; 4]; pixels] }),
        ..tiles[0].1.clone()
    };
    for (_, t) in &tiles {
        let (w, h) = t.region.size;
        for y in 0..h as usize {
            let src = y * w as usize;
            let dst = (t.region.origin.1 - y0) as usize * bounds.size.0 as usize
                + y * bounds.size.0 as usize
                + (t.region.origin.0 - x0) as usize;
            let n = w as usize;
            out.mean[dst..dst + n].copy_from_slice(&t.mean[src..src + n]);
            out.moment[dst..dst + n].copy_from_slice(&t.moment[src..src + n]);
            out.albedo[dst..dst + n].copy_from_slice(&t.albedo[src..src + n]);
            out.normal[dst..dst + n].copy_from_slice(&t.normal[src..src + n]);
            out.depth[dst..dst + n].copy_from_slice(&t.depth[src..src + n]);
            out.emission[dst..dst + n].copy_from_slice(&t.emission[src..src + n]);
            if let (Some(o), Some(c)) = (&mut out.coverage, &t.coverage) {
                o[dst..dst + n].copy_from_slice(&c[src..src + n]);
            }
            if let (Some(o), Some(l)) = (&mut out.lobe_split, &t.lobe_split) {
                o.specular[dst..dst + n].copy_from_slice(&l.specular[src..src + n]);
                o.split[dst..dst + n].copy_from_slice(&l.split[src..src + n]);
            }
        }
    }
    Ok(out)
}
