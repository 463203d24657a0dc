//! Cameras (perspective and orthographic), punctual lights, and the emissive table.

use crate::{khronos, load, read_glb, scenes_dir, to_glb};
use glam::Vec3;
use serde_json::json;
use umbra::scene::{LightKind, Scene};
use umbra::Error;

// ---------------------------------------------------------------------------------------------
// Cameras and lights

#[test]
fn cameras_are_selected_by_index_or_default_or_framed() {
    let cornell = Scene::cornell_box();
    let camera = cornell.camera(None).unwrap();
    assert_eq!(camera, cornell.cameras[0]);
    assert_eq!(cornell.camera(Some(0)).unwrap(), camera);
    let close = |a: [f32; 3], b: [f32; 3]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-5);
    assert!(close(camera.position, [0.275, 0.275, -0.8]), "{camera:?}");
    assert!(close(camera.forward, [0.0, 0.0, 1.0]) && close(camera.up, [0.0, 1.0, 0.0]), "{camera:?}");
    assert!((camera.yfov.to_degrees() - 39.3).abs() < 0.1 && camera.aspect == Some(1.0));
    match cornell.camera(Some(3)) {
        Err(Error::Scene { path, message }) => {
            assert!(path.to_string_lossy().contains("cornell-box.glb"));
            assert!(message.contains("no camera 3") && message.contains("1 camera"), "{message}");
        }
        other => panic!("expected an error, got {other:?}"),
    }

    // Box.glb has no camera: one is made that frames the bounds from +Z with a 45° yfov.
    let boxed = load(&khronos("Box"));
    assert!(boxed.cameras.is_empty());
    let framing = boxed.camera(None).unwrap();
    let (lo, hi) = boxed.bounds();
    let (centre, radius) =
        ((Vec3::from(lo) + Vec3::from(hi)) * 0.5, (Vec3::from(hi) - Vec3::from(lo)).length() * 0.5);
    assert_eq!((framing.forward, framing.up), ([0.0, 0.0, -1.0], [0.0, 1.0, 0.0]));
    assert!((framing.yfov.to_degrees() - 45.0).abs() < 1e-4);
    let eye = Vec3::from(framing.position);
    assert!(eye.x == centre.x && eye.y == centre.y && eye.z > centre.z);
    let half_angle = (radius / (eye - centre).length()).asin();
    assert!(half_angle <= framing.yfov * 0.5 + 1e-5, "the bounding sphere must fit");
    assert!(framing.znear > 0.0 && framing.znear < (eye - centre).length() - radius);
    assert!(
        matches!(boxed.camera(Some(0)), Err(Error::Scene { message, .. }) if message.contains("0 cameras"))
    );
}

#[test]
fn punctual_lights_are_placed_in_world_space() {
    let scene = load(&scenes_dir().join("textured.glb"));
    assert_eq!(scene.lights.len(), 2);
    let bulb = scene.lights.iter().find(|l| l.kind == LightKind::Point).unwrap();
    assert_eq!((bulb.position, bulb.intensity, bulb.range), ([1.0, 2.0, 1.0], 20.0, Some(10.0)));
    let spot = scene.lights.iter().find(|l| l.kind == LightKind::Spot).unwrap();
    assert!(Vec3::from(spot.direction).abs_diff_eq(-Vec3::Y, 1e-6), "{spot:?}");
    assert_eq!((spot.inner_cone_angle, spot.outer_cone_angle, spot.color), (0.2, 0.5, [1.0; 3]));
    let sun = &load(&scenes_dir().join("spheres.glb")).lights[0];
    assert_eq!(sun.kind, LightKind::Directional);
    assert!(Vec3::from(sun.direction).abs_diff_eq(Vec3::new(-0.4, -1.0, -0.6).normalize(), 1e-5));
}

// ---------------------------------------------------------------------------------------------
// The emissive table

#[test]
fn the_emissive_table_holds_exactly_the_lights_triangles() {
    let scene = Scene::cornell_box();
    let light = scene.materials.iter().position(|m| m.name == "light").unwrap() as u32;
    let want: Vec<u32> =
        (0..scene.triangles.len() as u32).filter(|&t| scene.triangle_material[t as usize] == light).collect();
    let table = &scene.emissive;
    assert_eq!(table.triangles, want);
    assert!(table.cdf.windows(2).all(|w| w[0] <= w[1]) && *table.cdf.last().unwrap() == 1.0);
    let soup = scene.triangle_soup();
    let areas: Vec<f32> = table
        .triangles
        .iter()
        .map(|&t| {
            let [a, b, c] = soup[t as usize];
            0.5 * (b - a).cross(c - a).length()
        })
        .collect();
    let total_area: f32 = areas.iter().sum();
    assert!((total_area - 0.13 * 0.105).abs() < 1e-6);
    for (i, area) in areas.iter().enumerate() {
        assert!((table.pmf(i) - area / total_area).abs() < 1e-5, "pmf of entry {i}");
    }
    let luminance = 0.2126 * 17.0 + 0.7152 * 12.0 + 0.0722 * 4.0;
    assert!((table.total_power - luminance * total_area * std::f32::consts::PI).abs() < 1e-4);
    // Sampling follows the cdf: u below the first step picks entry 0, above it entry 1.
    assert_eq!(table.sample(0.0).0, 0);
    assert_eq!(table.sample(table.cdf[0] * 0.99).0, 0);
    assert_eq!(table.sample(table.cdf[0] + 1e-3).0, 1);
    assert_eq!(table.sample(1.0).0, 1);
    let hits = (0..1000).filter(|i| table.sample((*i as f32 + 0.5) / 1000.0).0 == 0).count();
    assert!((hits as f32 / 1000.0 - table.pmf(0)).abs() < 2e-3);
    assert!(load(&khronos("Box")).emissive.is_empty());
}

/// A triangle the BVH build splits into pieces (early split clipping) appears once per piece in
/// BVH order, and every reference must carry the same shading record, its light pmf included:
/// the path tracer's MIS reads the pmf of whichever reference a ray hits.
#[test]
fn split_triangles_carry_their_shading_in_every_reference() {
    let mut scene = Scene { name: "split".into(), ..Default::default() };
    scene.materials.push(umbra::scene::Material::default());
    scene.materials.push(umbra::scene::Material { emissive: [4.0; 3], ..Default::default() });
    let mut add = |corners: [Vec3; 3], material: u32| {
        let base = scene.positions.len() as u32;
        scene.positions.extend(corners.map(<[f32; 3]>::from));
        scene.normals.extend([[0.0, 1.0, 0.0]; 3]);
        scene.triangles.push([base, base + 1, base + 2]);
        scene.triangle_material.push(material);
    };
    // Small triangles on a floor, a few of them emissive, and one large emissive ceiling.
    for i in 0..400 {
        let p = Vec3::new((i % 20) as f32 * 0.1 - 1.0, 0.0, (i / 20) as f32 * 0.1 - 1.0);
        add([p, p + Vec3::new(0.05, 0.0, 0.0), p + Vec3::new(0.0, 0.0, 0.05)], u32::from(i % 50 == 0));
    }
    let big = 400;
    add([Vec3::new(-10.0, 5.0, -10.0), Vec3::new(10.0, 5.0, -10.0), Vec3::new(0.0, 5.0, 10.0)], 1);
    scene.update_emissive();
    let arrays = umbra::gpu::scene::SceneArrays::new(&scene).unwrap();
    let references: Vec<usize> =
        (0..arrays.triangles.len()).filter(|&i| arrays.bvh.prim_order[i] == big).collect();
    assert!(references.len() > 1, "the large triangle was not split: {:?}", arrays.bvh.stats);
    let record = arrays.triangles[references[0]];
    assert!(record.light_pmf > 0.5, "{record:?}");
    for &i in &references {
        assert_eq!(arrays.triangles[i], record, "reference {i} of the split triangle differs");
    }
    for (i, t) in arrays.triangles.iter().enumerate() {
        let input = arrays.bvh.prim_order[i];
        assert_eq!(
            t.light_pmf > 0.0,
            input == big || (input < 400 && input.is_multiple_of(50)),
            "reference {i}"
        );
    }
}

/// An orthographic camera is read (xmag, ymag, znear, zfar, placed by its node) with no warning;
/// cameras keep the file's node order whatever their kind; a bad magnification or plane is an
/// error naming the camera.
#[test]
fn orthographic_cameras_are_read() {
    let (mut json, bin) = read_glb(&scenes_dir().join("textured.glb"));
    json["cameras"] = json!([
        {"type": "orthographic", "orthographic": {"xmag": 2.5, "ymag": 1.25, "znear": 0.1, "zfar": 10.0}},
        {"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.2}},
    ]);
    let first_node = json["nodes"].as_array().unwrap().len();
    json["nodes"].as_array_mut().unwrap().push(json!({"camera": 0, "translation": [1.0, 2.0, 5.0]}));
    json["nodes"].as_array_mut().unwrap().push(json!({"camera": 1}));
    let scene_index = json["scene"].as_u64().unwrap_or(0) as usize;
    for node in [first_node, first_node + 1] {
        json["scenes"][scene_index]["nodes"].as_array_mut().unwrap().push(json!(node));
    }
    let scene = Scene::from_glb_bytes("ortho.glb", &to_glb(&json, &bin)).unwrap();
    assert!(scene.warnings.iter().all(|w| !w.contains("camera")), "{:?}", scene.warnings);
    let cameras: Vec<_> =
        scene.cameras.iter().filter(|c| c.position == [1.0, 2.0, 5.0] || c.yfov == 0.5).collect();
    assert_eq!(cameras.len(), 2, "{:?}", scene.cameras);
    let (ortho, perspective) = (cameras[0], cameras[1]);
    assert_eq!(ortho.orthographic, Some(umbra::scene::Orthographic { xmag: 2.5, ymag: 1.25, zfar: 10.0 }));
    assert_eq!((ortho.znear, ortho.aspect), (0.1, Some(2.0)));
    assert_eq!((ortho.forward, ortho.up), ([0.0, 0.0, -1.0], [0.0, 1.0, 0.0]));
    assert_eq!((perspective.orthographic, perspective.znear), (None, 0.2));

    for (orthographic, problem) in [
        (json!({"xmag": 0.0, "ymag": 1.0, "znear": 0.1, "zfar": 10.0}), "xmag"),
        (json!({"xmag": 1.0, "ymag": 1.0, "znear": 2.0, "zfar": 1.0}), "zfar"),
    ] {
        json["cameras"][0]["orthographic"] = orthographic;
        let message = Scene::from_glb_bytes("ortho.glb", &to_glb(&json, &bin)).unwrap_err().to_string();
        assert!(
            message.contains("ortho.glb") && message.contains("camera 0") && message.contains(problem),
            "{message}"
        );
    }
}
