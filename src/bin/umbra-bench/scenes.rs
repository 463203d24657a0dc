//! The scenes the benchmarks run on: the generated terrain, glTF files, Sponza under a sun, the
//! path tracer's default set, and the camera they are seen from.

use crate::rays::RayScene;
use anyhow::Result;
use glam::Vec3;
use std::path::PathBuf;
use umbra::procedural::{icosphere, terrain};

/// Generated terrain with a row of spheres on it: `2·n²` + 15,360 triangles.
pub(crate) fn terrain_scene(name: &str, n: u32) -> RayScene {
    let size = 100.0;
    let mut triangles = terrain(n, size, 3).soup();
    for k in 0..3 {
        triangles.extend(icosphere(4, Vec3::new(-20.0 + 20.0 * k as f32, 8.0, 0.0), 6.0).soup());
    }
    RayScene {
        name: format!("{name} ({} triangles)", triangles.len()),
        triangles,
        eye: Vec3::new(0.0, 30.0, 70.0),
        target: Vec3::new(0.0, 0.0, -10.0),
        yfov: 50f32.to_radians(),
        light: Vec3::new(30.0, 60.0, 20.0),
    }
}

/// The file's first perspective camera (the ray benchmark's rays are a pinhole's) or, when it has
/// none, one inside the bounds looking along their longest horizontal axis (the classic view down
/// Sponza's atrium; every primary ray hits).
pub(crate) fn bench_camera(scene: &umbra::scene::Scene) -> umbra::scene::Camera {
    let (lo, hi) = scene.bounds();
    let (lo, hi) = (Vec3::from(lo), Vec3::from(hi));
    match scene.cameras.iter().find(|c| c.orthographic.is_none()) {
        Some(c) => *c,
        None => {
            let (center, extent) = ((lo + hi) * 0.5, hi - lo);
            let axis = if extent.x >= extent.z { Vec3::X } else { Vec3::Z };
            let eye = Vec3::new(center.x, lo.y + 0.25 * extent.y, center.z) - axis * 0.35 * extent.dot(axis);
            umbra::scene::Camera {
                position: eye.into(),
                forward: (Vec3::new(center.x, eye.y, center.z) - eye).normalize().into(),
                up: [0.0, 1.0, 0.0],
                yfov: 60f32.to_radians(),
                aspect: None,
                znear: 0.01,
                orthographic: None,
                jitter: [0.0; 2],
            }
        }
    }
}

/// A glTF file's triangles, lit by a point light just under the top of the bounds, seen from
/// [`bench_camera`]. Only the geometry counts here, so absent image files are warned about and
/// left out, as in `umbra-bench paths`.
pub(crate) fn gltf_scene(path: &std::path::Path) -> Result<RayScene> {
    let (_, scene) = load_path_scene(path)?;
    let (lo, hi) = scene.bounds();
    let (lo, hi) = (Vec3::from(lo), Vec3::from(hi));
    let camera = bench_camera(&scene);
    let position = Vec3::from(camera.position);
    let triangles = scene.triangle_soup();
    let name =
        path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned());
    Ok(RayScene {
        name: format!("{name} ({} triangles)", triangles.len()),
        triangles,
        eye: position,
        target: position + Vec3::from(camera.forward),
        yfov: camera.yfov,
        light: Vec3::new((lo.x + hi.x) * 0.5, hi.y - (hi.y - lo.y) * 0.05, (lo.z + hi.z) * 0.5),
    })
}

/// The sun the benchmarks add to scenes without punctual lights.
pub(crate) const DEFAULT_SUN: [f32; 3] = [0.25, -1.0, 0.15];

/// Adds a directional light of 5 lux shining along `direction`.
pub(crate) fn add_sun(scene: &mut umbra::scene::Scene, direction: [f32; 3]) {
    scene.lights.push(umbra::scene::Light {
        name: "sun".into(),
        kind: umbra::scene::LightKind::Directional,
        position: [0.0; 3],
        direction: Vec3::from(direction).normalize().into(),
        color: [1.0; 3],
        intensity: 5.0,
        range: None,
        inner_cone_angle: 0.0,
        outer_cone_angle: std::f32::consts::PI,
    });
}

/// The `--gltf` scenes, each keyed by its file stem.
pub(crate) fn load_gltf(gltf: &[PathBuf]) -> Result<Vec<(String, umbra::scene::Scene)>> {
    gltf.iter()
        .map(|path| {
            let key = path.file_stem().map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned());
            Ok((key, umbra::scene::Scene::load(path)?))
        })
        .collect()
}

/// `path`, or else `$UMBRA_ASSETS/gltf/<within>` (the external asset collection, as the tests read
/// it); `None` when neither names one: nothing reads a folder beside the checkout unasked.
pub(crate) fn external(path: Option<PathBuf>, within: &str) -> Option<PathBuf> {
    path.or_else(|| std::env::var_os("UMBRA_ASSETS").map(|d| PathBuf::from(d).join("gltf").join(within)))
}

/// Dabrovic Sponza from `path` (or `$UMBRA_ASSETS`) under the default sun, keyed `sponza-sun`;
/// left out, saying why, when neither names it or it does not load.
pub(crate) fn sponza_under_a_sun(path: Option<&std::path::Path>) -> Option<(String, umbra::scene::Scene)> {
    let Some(path) = external(path.map(PathBuf::from), "SponzaDabrovic/sponza_dabrovic.glb") else {
        log::warn!("skipping Sponza under a sun: give --sponza PATH or set UMBRA_ASSETS");
        return None;
    };
    match umbra::scene::Scene::load(&path) {
        Ok(mut scene) => {
            add_sun(&mut scene, DEFAULT_SUN);
            let stem = path.file_stem().map_or_else(|| "sponza".into(), |s| s.to_string_lossy().into_owned());
            scene.name = format!("{stem} under a sun");
            Some(("sponza-sun".into(), scene))
        }
        Err(e) => {
            log::warn!("skipping Sponza under a sun: {e}");
            None
        }
    }
}

/// `umbra-bench paths`'s default set: the embedded Cornell box, the repository's scenes/*.glb
/// and one file of each model folder under `assets` (skipped with a warning when absent): its
/// first .glb, else its glTF-Binary's, else its first .gltf, else its glTF folder's.
pub(crate) fn default_path_scenes(
    assets: Option<&std::path::Path>,
) -> Result<Vec<(String, umbra::scene::Scene)>> {
    let files_in = |dir: &std::path::Path, ext: &str| -> Vec<PathBuf> {
        let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
            .into_iter()
            .flatten()
            .flatten()
            .map(|e| e.path())
            .filter(|p| p.extension().is_some_and(|e| e == ext))
            .collect();
        files.sort();
        files
    };
    let mut files = files_in(std::path::Path::new("scenes"), "glb");
    match assets.map(|dir| (dir, std::fs::read_dir(dir))) {
        None => log::warn!("no --assets and no UMBRA_ASSETS: the sample models are left out"),
        Some((_, Ok(entries))) => {
            let mut models: Vec<PathBuf> =
                entries.flatten().map(|e| e.path()).filter(|p| p.is_dir()).collect();
            models.sort();
            for model in models {
                let mut found = files_in(&model, "glb");
                found.extend(files_in(&model.join("glTF-Binary"), "glb"));
                found.extend(files_in(&model, "gltf"));
                found.extend(files_in(&model.join("glTF"), "gltf"));
                files.extend(found.into_iter().next());
            }
        }
        Some((dir, Err(e))) => log::warn!("{}: {e}; the sample models are left out", dir.display()),
    }
    // One that does not load at all is left out with its error.
    let mut scenes = vec![("cornell-box (embedded)".to_string(), umbra::scene::Scene::cornell_box())];
    for path in files {
        match load_path_scene(&path) {
            Ok(scene) => scenes.push(scene),
            Err(e) => log::warn!("{e}; left out"),
        }
    }
    Ok(scenes)
}

/// `umbra-bench paths`'s scenes named on the command line, each keyed by its file stem and
/// loaded as the default set's are (so one row of its table can be measured alone); one that
/// does not load is an error.
pub(crate) fn named_path_scenes(files: &[PathBuf]) -> Result<Vec<(String, umbra::scene::Scene)>> {
    files
        .iter()
        .map(|path| {
            let (name, scene) = load_path_scene(path)?;
            Ok((path.file_stem().map_or(name, |s| s.to_string_lossy().into_owned()), scene))
        })
        .collect()
}

/// A scene of `umbra-bench paths`, keyed by its file name. A sample model whose image files are
/// absent renders with its factors alone (a warning each).
pub(crate) fn load_path_scene(path: &std::path::Path) -> Result<(String, umbra::scene::Scene)> {
    let options = umbra::scene::LoadOptions {
        missing_textures: umbra::scene::MissingTextures::Warn,
        ..Default::default()
    };
    let name =
        path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned());
    Ok((name, umbra::scene::Scene::load_with(path, &options)?))
}
