//! Animations posed at a time (`LoadOptions::pose`, `umbra render --time`): node translation,
//! rotation and scale, morph weights and skins, by `STEP`, `LINEAR` (rotations by slerp) and
//! `CUBICSPLINE`, each against values computed here from the specification's formulas (glTF 2.0,
//! Appendix C) and trigonometry, not from the loader's code. CPU only.

#[path = "support/generate.rs"]
mod generate;

mod common;

use serde_json::{json, Value};
use umbra::scene::{AnimationSelect, LoadOptions, PoseAt, Scene};

/// A file of one triangle, (0,0,0), (1,0,0), (0,1,0), placed by node 0, and the animations added.
struct File {
    json: Value,
    bin: Vec<u8>,
}

impl File {
    fn new() -> Self {
        let mut f = File { json: json!({}), bin: Vec::new() };
        f.json = json!({
            "asset": {"version": "2.0"},
            "scene": 0,
            "scenes": [{"nodes": [0]}],
            "nodes": [{"mesh": 0}],
            "meshes": [{"primitives": [{"attributes": {}}]}],
            "buffers": [{}],
            "bufferViews": [],
            "accessors": [],
            "animations": [],
        });
        let p = f.accessor(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0], "VEC3");
        f.json["accessors"][p]["min"] = json!([0.0, 0.0, 0.0]);
        f.json["accessors"][p]["max"] = json!([1.0, 1.0, 0.0]);
        f.json["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(p);
        f
    }

    /// A float accessor of `data` as `ty` elements.
    fn accessor(&mut self, data: &[f32], ty: &str) -> usize {
        let n = match ty {
            "SCALAR" => 1,
            "VEC3" => 3,
            "VEC4" => 4,
            _ => panic!("{ty}"),
        };
        let at = self.bin.len();
        for x in data {
            self.bin.extend_from_slice(&x.to_le_bytes());
        }
        let views = self.json["bufferViews"].as_array_mut().unwrap();
        views.push(json!({"buffer": 0, "byteOffset": at, "byteLength": data.len() * 4}));
        let view = views.len() - 1;
        let accessors = self.json["accessors"].as_array_mut().unwrap();
        accessors
            .push(json!({"bufferView": view, "componentType": 5126, "count": data.len() / n, "type": ty}));
        accessors.len() - 1
    }

    /// Adds animation `name` with one channel: `path` of node `node`.
    fn animate(
        &mut self,
        name: &str,
        node: usize,
        path: &str,
        interpolation: &str,
        times: &[f32],
        values: &[f32],
    ) {
        let input = self.accessor(times, "SCALAR");
        self.json["accessors"][input]["min"] = json!([times[0]]);
        self.json["accessors"][input]["max"] = json!([times[times.len() - 1]]);
        let ty = match path {
            "rotation" => "VEC4",
            "weights" => "SCALAR",
            _ => "VEC3",
        };
        let output = self.accessor(values, ty);
        self.json["animations"].as_array_mut().unwrap().push(json!({
            "name": name,
            "samplers": [{"input": input, "output": output, "interpolation": interpolation}],
            "channels": [{"sampler": 0, "target": {"node": node, "path": path}}],
        }));
    }

    /// Writes the file into the temporary folder: its path.
    fn write(&self) -> std::path::PathBuf {
        let mut json = self.json.clone();
        json["buffers"][0]["byteLength"] = json!(self.bin.len());
        let bytes = generate::glb(&serde_json::to_vec(&json).unwrap(), &self.bin);
        let dir = std::env::temp_dir().join(format!("umbra-animation-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path =
            dir.join(format!("{}.glb", std::thread::current().name().unwrap_or("t").replace("::", "-")));
        std::fs::write(&path, bytes).unwrap();
        path
    }

    fn load(&self, time: Option<f32>, animations: AnimationSelect) -> umbra::Result<Scene> {
        let path = self.write();
        let options =
            LoadOptions { pose: time.map(|time| PoseAt { time, animations }), ..Default::default() };
        Scene::load_with(&path, &options)
    }

    fn at(&self, time: f32) -> Scene {
        self.load(Some(time), AnimationSelect::All).unwrap()
    }
}

/// Where vertex `v` of the triangle (0: the origin, 1: +x, 2: +y) landed.
fn vertex(scene: &Scene, v: usize) -> [f32; 3] {
    scene.positions[scene.triangles[0][v] as usize]
}

fn close(a: [f32; 3], b: [f32; 3], tolerance: f32) -> bool {
    (0..3).all(|k| (a[k] - b[k]).abs() <= tolerance)
}

/// LINEAR translation: the lerp of the keys around the time; before the first key the first
/// value, after the last the last; without a time, the default transform and the warning that
/// the file moves.
#[test]
fn linear_translation_interpolates_and_holds_its_ends() {
    let mut f = File::new();
    f.animate("move", 0, "translation", "LINEAR", &[1.0, 3.0], &[0.0, 0.0, 0.0, 4.0, 2.0, 0.0]);
    assert_eq!(vertex(&f.at(2.0), 0), [2.0, 1.0, 0.0]);
    assert_eq!(vertex(&f.at(2.5), 0), [3.0, 1.5, 0.0]);
    assert_eq!(vertex(&f.at(0.0), 0), [0.0, 0.0, 0.0]);
    assert_eq!(vertex(&f.at(10.0), 0), [4.0, 2.0, 0.0]);
    let still = f.load(None, AnimationSelect::All).unwrap();
    assert_eq!(vertex(&still, 0), [0.0, 0.0, 0.0]);
    assert!(still.warnings.iter().any(|w| w.contains("animated")), "{:?}", still.warnings);
    assert!(f.at(2.0).warnings.is_empty(), "{:?}", f.at(2.0).warnings);
}

/// STEP holds each key's value until the next key.
#[test]
fn step_holds_each_key() {
    let mut f = File::new();
    f.animate(
        "hop",
        0,
        "translation",
        "STEP",
        &[0.0, 1.0, 2.0],
        &[0.0, 0.0, 0.0, 5.0, 0.0, 0.0, 9.0, 0.0, 0.0],
    );
    for (time, x) in [(0.5, 0.0), (0.999, 0.0), (1.0, 5.0), (1.5, 5.0), (2.0, 9.0), (7.0, 9.0)] {
        assert_eq!(vertex(&f.at(time), 0)[0], x, "at {time}");
    }
}

/// LINEAR rotation: a quarter turn about +z at a quarter of the way is 22.5° (slerp turns at a
/// constant rate), along the shorter arc even when the second key is given as its negation.
#[test]
fn rotation_slerps_along_the_shorter_arc() {
    let h = std::f32::consts::FRAC_1_SQRT_2;
    for sign in [1.0, -1.0] {
        let mut f = File::new();
        f.animate(
            "turn",
            0,
            "rotation",
            "LINEAR",
            &[0.0, 1.0],
            &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, sign * h, sign * h],
        );
        let angle = 22.5f32.to_radians();
        let got = vertex(&f.at(0.25), 1);
        assert!(close(got, [angle.cos(), angle.sin(), 0.0], 1e-6), "sign {sign}: {got:?}");
    }
}

/// CUBICSPLINE: p(s) = (2s³ − 3s² + 1) v0 + td (s³ − 2s² + s) b0 + (−2s³ + 3s²) v1 + td (s³ − s²) a1
/// with td the keys' interval, b0 the first key's out-tangent and a1 the second's in-tangent.
#[test]
fn cubic_spline_is_the_hermite_spline_of_the_keys() {
    let (a0, v0, b0) = ([9.0, 9.0, 9.0], [0.0, 1.0, 0.0], [2.0, -1.0, 0.5]);
    let (a1, v1, b1) = ([-3.0, 0.0, 1.0], [4.0, 0.0, 2.0], [7.0, 7.0, 7.0]);
    let values: Vec<f32> = [a0, v0, b0, a1, v1, b1].iter().flatten().copied().collect();
    let mut f = File::new();
    f.animate("curve", 0, "translation", "CUBICSPLINE", &[1.0, 3.0], &values);
    let td = 2.0f32;
    for time in [1.0f32, 1.4, 2.0, 2.9, 3.0] {
        let s = (time - 1.0) / td;
        let (s2, s3) = (s * s, s * s * s);
        let expected: [f32; 3] = std::array::from_fn(|k| {
            (2.0 * s3 - 3.0 * s2 + 1.0) * v0[k]
                + td * (s3 - 2.0 * s2 + s) * b0[k]
                + (-2.0 * s3 + 3.0 * s2) * v1[k]
                + td * (s3 - s2) * a1[k]
        });
        let got = vertex(&f.at(time), 0);
        assert!(close(got, expected, 1e-5), "at {time}: {got:?} vs {expected:?}");
    }
}

/// Morph weights: the vertices move by the interpolated weight × the target's displacement.
#[test]
fn morph_weights_animate() {
    let mut f = File::new();
    let delta = f.accessor(&[0.0, 0.0, 1.0, 0.0, 0.0, 2.0, 0.0, 0.0, 4.0], "VEC3");
    f.json["accessors"][delta]["min"] = json!([0.0, 0.0, 1.0]);
    f.json["accessors"][delta]["max"] = json!([0.0, 0.0, 4.0]);
    f.json["meshes"][0]["primitives"][0]["targets"] = json!([{"POSITION": delta}]);
    f.animate("breathe", 0, "weights", "LINEAR", &[0.0, 2.0], &[0.0, 1.0]);
    let scene = f.at(0.5);
    for (v, dz) in [(0, 1.0), (1, 2.0), (2, 4.0)] {
        assert_eq!(vertex(&scene, v)[2], 0.25 * dz, "vertex {v}");
    }
}

/// A skin follows its animated joint: every vertex bound to joint node 1 with weight 1 and an
/// identity inverse bind matrix moves with the joint's animated translation.
#[test]
fn skins_follow_their_animated_joints() {
    let mut f = File::new();
    let joints = f.bin.len();
    f.bin.extend_from_slice(&[0u8; 12]);
    let weights = f.accessor(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0], "VEC4");
    let views = f.json["bufferViews"].as_array_mut().unwrap();
    views.push(json!({"buffer": 0, "byteOffset": joints, "byteLength": 12}));
    let view = views.len() - 1;
    let accessors = f.json["accessors"].as_array_mut().unwrap();
    accessors.push(json!({"bufferView": view, "componentType": 5121, "count": 3, "type": "VEC4"}));
    let joints = accessors.len() - 1;
    let attributes = &mut f.json["meshes"][0]["primitives"][0]["attributes"];
    attributes["JOINTS_0"] = json!(joints);
    attributes["WEIGHTS_0"] = json!(weights);
    f.json["nodes"] = json!([{"mesh": 0, "skin": 0}, {"translation": [0.0, 0.0, 0.0]}]);
    f.json["scenes"] = json!([{"nodes": [0, 1]}]);
    f.json["skins"] = json!([{"joints": [1]}]);
    f.animate("lift", 1, "translation", "LINEAR", &[0.0, 1.0], &[0.0, 0.0, 0.0, 0.0, 3.0, 0.0]);
    let scene = f.at(0.5);
    assert_eq!(vertex(&scene, 1), [1.0, 1.5, 0.0]);
    assert_eq!(vertex(&scene, 2), [0.0, 2.5, 0.0]);
}

/// `--animation`: by index or name only that animation plays; an unknown one is an error naming
/// the file's animations.
#[test]
fn one_animation_can_be_chosen() {
    let mut f = File::new();
    f.animate("slide", 0, "translation", "LINEAR", &[0.0, 1.0], &[0.0, 0.0, 0.0, 2.0, 0.0, 0.0]);
    f.animate("grow", 0, "scale", "LINEAR", &[0.0, 1.0], &[1.0, 1.0, 1.0, 3.0, 3.0, 3.0]);
    let both = f.at(1.0);
    assert_eq!(vertex(&both, 1), [5.0, 0.0, 0.0]);
    let slide = f.load(Some(1.0), AnimationSelect::Name("slide".into())).unwrap();
    assert_eq!(vertex(&slide, 1), [3.0, 0.0, 0.0]);
    let grow = f.load(Some(1.0), AnimationSelect::Index(1)).unwrap();
    assert_eq!(vertex(&grow, 1), [3.0, 0.0, 0.0]);
    assert_eq!(vertex(&grow, 0), [0.0, 0.0, 0.0]);
    let error = f.load(Some(1.0), AnimationSelect::Name("jump".into())).unwrap_err().to_string();
    assert!(error.contains("no animation 'jump'") && error.contains("'slide', 'grow'"), "{error}");
    let error = f.load(Some(1.0), AnimationSelect::Index(5)).unwrap_err().to_string();
    assert!(error.contains("no animation 5"), "{error}");
}

/// `umbra render --frames A..B --fps F -o frame-%02d.png`: one image per frame (A up to B), frame f
/// posed at f / F seconds, named by the pattern; the triangle's slide moves it across a fixed
/// camera's view, so the frames differ. A pattern without a frame field is refused before any
/// render.
#[test]
fn frames_render_one_image_each() {
    let mut f = File::new();
    f.json["nodes"] = json!([{"mesh": 0}, {"camera": 0, "translation": [0.5, 0.5, 4.0]}]);
    f.json["scenes"] = json!([{"nodes": [0, 1]}]);
    f.json["cameras"] = json!([{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}]);
    // Red under a grey sky: the triangle shows against the background.
    f.json["materials"] =
        json!([{"pbrMetallicRoughness": {"baseColorFactor": [1, 0, 0, 1], "metallicFactor": 0}}]);
    f.json["meshes"][0]["primitives"][0]["material"] = json!(0);
    f.animate("slide", 0, "translation", "LINEAR", &[0.0, 1.0], &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0]);
    let scene = f.write();
    let dir = scene.with_extension("frames");
    std::fs::create_dir_all(&dir).unwrap();
    let umbra = || std::process::Command::new(env!("CARGO_BIN_EXE_umbra"));
    common::run_validated(
        umbra()
            .arg("render")
            .arg(&scene)
            .args(["--mode", "hybrid", "--size", "32x24", "--env-color", "0.5,0.5,0.5"])
            .args(["--frames", "0..3", "--fps", "2", "-o"])
            .arg(dir.join("frame-%02d.png")),
    );
    let frames: Vec<Vec<u8>> = (0..3)
        .map(|k| std::fs::read(dir.join(format!("frame-{k:02}.png"))).expect("the frame's image"))
        .collect();
    assert!(!dir.join("frame-03.png").exists(), "frame B was rendered");
    assert!(frames[0] != frames[1] && frames[1] != frames[2], "the frames do not move");
    let out = umbra()
        .arg("render")
        .arg(&scene)
        .args(["--frames", "0..2", "-o"])
        .arg(dir.join("still.png"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && stderr.contains("frame number field"), "{stderr}");
}

/// `Scene::pose` on a loaded scene gives exactly what loading the file at that time gives (every
/// vertex, triangle, instance, camera and light), for every animation kind in `animated.glb`
/// (a skin, a rigid node, a morph weight); a scene without animations says so.
#[test]
fn posing_a_loaded_scene_equals_loading_it_at_that_time() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/animated.glb");
    let mut scene = Scene::load(&path).unwrap();
    let rest = scene.positions.clone();
    for (time, animations) in [
        (0.3, AnimationSelect::All),
        (1.7, AnimationSelect::Name("bend".into())),
        (0.9, AnimationSelect::Index(2)),
    ] {
        let at = PoseAt { time, animations };
        scene.pose(&at).unwrap();
        let loaded =
            Scene::load_with(&path, &LoadOptions { pose: Some(at.clone()), ..Default::default() }).unwrap();
        assert_eq!(scene.positions, loaded.positions, "{at:?}");
        assert_eq!(scene.normals, loaded.normals, "{at:?}");
        assert_eq!(scene.triangles, loaded.triangles, "{at:?}");
        assert_eq!(scene.instances, loaded.instances, "{at:?}");
        assert_eq!(scene.lights, loaded.lights, "{at:?}");
        assert_eq!(scene.cameras, loaded.cameras, "{at:?}");
        assert_eq!(scene.content_hash(), loaded.content_hash(), "{at:?}");
        assert_ne!(scene.positions, rest, "{at:?} moved nothing");
    }
    let mut still = Scene::cornell_box();
    let error = still.pose(&PoseAt { time: 1.0, animations: AnimationSelect::All }).unwrap_err().to_string();
    assert!(error.contains("has no animations to pose"), "{error}");
}

/// A refitted BVH finds, ray for ray, the hit a brute-force search over the posed triangles
/// finds (the same triangle, distance and barycentrics), and its boxes still hold their
/// triangles (`Bvh::validate`), after posing far from the rest pose it was built for.
#[test]
fn a_refitted_bvh_finds_what_brute_force_finds() {
    use glam::Vec3;
    use umbra::bvh::{reference::Reference, Bvh, Ray};
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/animated.glb");
    let mut scene = Scene::load(&path).unwrap();
    let mut bvh = Bvh::build(&scene.triangle_soup()).unwrap();
    scene.pose(&PoseAt { time: 1.0, animations: AnimationSelect::All }).unwrap();
    let soup = scene.triangle_soup();
    bvh.refit(&soup, &[]).unwrap();
    bvh.validate().unwrap();
    let reference = Reference::new(&soup);
    let mut state = 0x1234_5678_u32;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 17;
        state ^= state << 5;
        state as f32 / u32::MAX as f32
    };
    let mut hits = 0;
    for _ in 0..4000 {
        let origin = Vec3::new(next() * 6.0 - 3.0, next() * 2.5, next() * 6.0 - 3.0);
        let dir = Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5).normalize();
        let ray = Ray { origin, dir, tmin: 0.0, tmax: f32::MAX };
        let expected = reference.closest(&ray);
        let got = bvh.closest(&ray);
        hits += usize::from(expected.is_some());
        assert!(
            umbra::bvh::reference::same_hit(got, expected, |i| bvh.prim_order[i as usize]),
            "ray {ray:?}: refitted {got:?}, brute force {expected:?}"
        );
    }
    assert!(hits > 1000, "only {hits} of 4000 rays hit: the test sees too little");
}

/// `--frames` carries the device, the loaded file and the kernels from frame to frame, posing the
/// scene again and refitting (or rebuilding) its BVH: each frame's image is byte for byte the one
/// a render of that time alone gives (`--time`), path-traced, for both `--bvh` choices.
#[test]
fn frames_equal_renders_of_each_time_alone() {
    let scene = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/animated.glb");
    let dir = std::env::temp_dir().join(format!("umbra-frames-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let umbra = || std::process::Command::new(env!("CARGO_BIN_EXE_umbra"));
    let common = ["--mode", "pathtrace", "--size", "40x30", "--spp", "2"];
    for bvh in ["refit", "rebuild"] {
        common::run_validated(
            umbra()
                .arg("render")
                .arg(&scene)
                .args(common)
                .args(["--frames", "1..4", "--fps", "3", "--bvh", bvh, "-o"])
                .arg(dir.join(format!("{bvh}-%d.png"))),
        );
        for frame in 1..4 {
            let alone = dir.join(format!("alone-{frame}.png"));
            if !alone.exists() {
                common::run_validated(
                    umbra()
                        .arg("render")
                        .arg(&scene)
                        .args(common)
                        .args(["--time", &format!("{}", frame as f32 / 3.0), "-o"])
                        .arg(&alone),
                );
            }
            let framed = std::fs::read(dir.join(format!("{bvh}-{frame}.png"))).unwrap();
            assert!(
                framed == std::fs::read(&alone).unwrap(),
                "--bvh {bvh}: frame {frame} differs from --time"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--frames` over a file without animations renders the same image every frame (nothing to
/// pose, the GPU scene kept) and says so once.
#[test]
fn frames_of_a_still_file_are_one_image_with_a_warning() {
    let scene = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.glb");
    let dir = std::env::temp_dir().join(format!("umbra-still-frames-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let stderr = common::run_validated(
        std::process::Command::new(env!("CARGO_BIN_EXE_umbra"))
            .arg("render")
            .arg(&scene)
            .args(["--mode", "hybrid", "--size", "32x24", "--frames", "0..2", "-o"])
            .arg(dir.join("f-%d.png")),
    );
    assert_eq!(stderr.matches("the file has no animations").count(), 1, "{stderr}");
    let [a, b] = [0, 1].map(|k| std::fs::read(dir.join(format!("f-{k}.png"))).unwrap());
    assert!(a == b, "a still file's frames differ");
    let _ = std::fs::remove_dir_all(&dir);
}
