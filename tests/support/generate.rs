//! The generator of umbra's own test scenes (`scenes/*.glb`), deterministic to the byte.
//!
//! One file serves two targets: `examples/gen_scenes.rs` writes the scenes into `scenes/`, and
//! `tests/scene/` regenerates them in memory and requires the committed files to be identical,
//! so the two cannot drift. It builds the glTF JSON with `serde_json` and writes GLB by hand.
//!
//! Scenes are in metres, +Y up. Every mesh is checked here to be wound counter-clockwise around
//! its normals, so the loader tests can trust the files.
#![allow(dead_code)]

use glam::{Mat3, Quat, Vec2, Vec3};
use image::ImageEncoder;
use serde_json::{json, Map, Value};

/// Every generated scene: file name and GLB bytes.
pub fn all() -> Vec<(&'static str, Vec<u8>)> {
    vec![
        ("cornell-box.glb", cornell_box()),
        ("spheres.glb", spheres()),
        ("textured.glb", textured()),
        ("instanced.glb", instanced()),
        ("glass.glb", glass()),
        ("many-lights.glb", many_lights()),
        ("animated.glb", animated()),
    ]
}

/// A GLB file: 12-byte header, JSON chunk padded with spaces, BIN chunk (if any) padded with
/// zeros.
pub fn glb(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let padded = |n: usize| n.div_ceil(4) * 4;
    let bin_chunk = if bin.is_empty() { 0 } else { 8 + padded(bin.len()) };
    let total = 12 + 8 + padded(json.len()) + bin_chunk;
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(padded(json.len()) as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(json);
    out.resize(20 + padded(json.len()), b' ');
    if !bin.is_empty() {
        out.extend_from_slice(&(padded(bin.len()) as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(bin);
        out.resize(total, 0);
    }
    out
}

/// The JSON document and BIN chunk of a GLB file (for tests that edit a file).
pub fn split_glb(glb: &[u8]) -> (Value, Vec<u8>) {
    let word = |at: usize| u32::from_le_bytes(glb[at..at + 4].try_into().unwrap()) as usize;
    let json_len = word(12);
    let json = serde_json::from_slice(&glb[20..20 + json_len]).expect("GLB JSON chunk");
    let bin = if glb.len() > 20 + json_len {
        glb[28 + json_len..28 + json_len + word(20 + json_len)].to_vec()
    } else {
        Vec::new()
    };
    (json, bin)
}

// ---------------------------------------------------------------------------------------------
// Scenes

/// The classic Cornell box, 0.55 m, open at the front (-Z), lit by a ceiling quad of radiance
/// (17, 12, 4). Red wall on the camera's left (+X), green on its right.
pub fn cornell_box() -> Vec<u8> {
    let mut g = Gltf::new();
    let white = g.material("white", [0.73, 0.73, 0.73], 0.0, 1.0);
    let red = g.material("red", [0.65, 0.05, 0.05], 0.0, 1.0);
    let green = g.material("green", [0.12, 0.45, 0.15], 0.0, 1.0);
    let light = g.push("materials", json!({
        "name": "light",
        "pbrMetallicRoughness": { "baseColorFactor": [0.78, 0.78, 0.78, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0 },
        "emissiveFactor": [1.0, 12.0 / 17.0, 4.0 / 17.0],
        "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": 17.0 } }
    }));
    let (s, h) = (0.55f32, 0.275f32);
    let c = |x, y, z| Vec3::new(x, y, z);
    let mut neutral = Mesh::default();
    neutral.quad(c(h, 0.0, h), c(h, 0.0, 0.0), c(0.0, 0.0, -h)); // floor, +Y
    neutral.quad(c(h, s, h), c(h, 0.0, 0.0), c(0.0, 0.0, h)); // ceiling, -Y
    neutral.quad(c(h, h, s), c(-h, 0.0, 0.0), c(0.0, h, 0.0)); // back, -Z
    let mut left = Mesh::default();
    left.quad(c(s, h, h), c(0.0, 0.0, h), c(0.0, h, 0.0)); // x = 0.55, -X
    let mut right = Mesh::default();
    right.quad(c(0.0, h, h), c(0.0, 0.0, -h), c(0.0, h, 0.0)); // x = 0, +X
    let (neutral, left, right) = (neutral.bare(), left.bare(), right.bare());
    let walls = vec![g.primitive(&neutral, white), g.primitive(&left, red), g.primitive(&right, green)];
    let walls = g.mesh("walls", walls);
    let mut lamp = Mesh::default();
    lamp.quad(c(0.278, 0.5488, 0.2795), c(0.065, 0.0, 0.0), c(0.0, 0.0, 0.0525)); // -Y, just below the ceiling
    let lamp = vec![g.primitive(&lamp.bare(), light)];
    let lamp = g.mesh("light", lamp);
    let block = vec![g.primitive(&Mesh::cuboid().bare(), white)];
    let block = g.mesh("block", block);

    let nodes = vec![
        g.push("nodes", json!({ "name": "walls", "mesh": walls })),
        g.push("nodes", json!({ "name": "light", "mesh": lamp })),
        g.push("nodes", json!({ "name": "short block", "mesh": block,
            "translation": [0.1855, 0.0825, 0.169], "rotation": y_rotation(-17.0), "scale": [0.165, 0.165, 0.165] })),
        g.push("nodes", json!({ "name": "tall block", "mesh": block,
            "translation": [0.3685, 0.165, 0.3513], "rotation": y_rotation(17.2), "scale": [0.165, 0.33, 0.165] })),
        g.camera_node("camera", [0.275, 0.275, -0.8], y_rotation(180.0), 2.0 * (0.0125f64 / 0.035).atan(), 1.0),
    ];
    g.finish(nodes, &["KHR_materials_emissive_strength"])
}

/// A 7×7 grid of spheres, roughness 0..1 along +X and metallic 0..1 along +Z, on a grey floor,
/// lit by one directional light.
pub fn spheres() -> Vec<u8> {
    let mut g = Gltf::new();
    let sphere = g.geometry(&Mesh::uv_sphere(0.4, 24, 12));
    let mut nodes = Vec::new();
    for m in 0..7 {
        for r in 0..7 {
            let (metallic, roughness) = (m as f64 / 6.0, r as f64 / 6.0);
            let material = g.material(
                &format!("metallic {metallic:.2} roughness {roughness:.2}"),
                [0.9, 0.5, 0.2],
                metallic,
                roughness,
            );
            let mesh = g.push("meshes", json!({ "name": format!("sphere m{m} r{r}"), "primitives": [sphere.with_material(material)] }));
            let name = format!("sphere m{m} r{r}");
            nodes.push(g.push(
                "nodes",
                json!({ "name": name, "mesh": mesh, "translation": [r as f64 - 3.0, 0.4, m as f64 - 3.0] }),
            ));
        }
    }
    let grey = g.material("floor", [0.5, 0.5, 0.5], 0.0, 0.8);
    let mut floor = Mesh::default();
    floor.quad(Vec3::ZERO, Vec3::new(5.0, 0.0, 0.0), Vec3::new(0.0, 0.0, -5.0));
    let floor = vec![g.primitive(&floor.bare(), grey)];
    let floor = g.mesh("floor", floor);
    nodes.push(g.push("nodes", json!({ "name": "floor", "mesh": floor })));
    nodes.push(g.camera_node(
        "camera",
        [0.0, 5.5, 8.5],
        look_rotation(Vec3::new(0.0, 5.5, 8.5), Vec3::ZERO),
        0.7,
        1.5,
    ));
    let sun =
        g.light(json!({ "name": "sun", "type": "directional", "color": [1.0, 0.96, 0.9], "intensity": 3.0 }));
    let towards = Vec3::new(-0.4, -1.0, -0.6).normalize();
    nodes.push(g.push(
        "nodes",
        json!({ "name": "sun", "rotation": quat(Quat::from_rotation_arc(-Vec3::Z, towards)),
        "extensions": { "KHR_lights_punctual": { "light": sun } } }),
    ));
    g.finish(nodes, &["KHR_lights_punctual"])
}

/// A plane and a cube with embedded PNG textures: an sRGB checker (with `KHR_texture_transform`
/// and a mirrored/clamped nearest sampler on the plane), a bumpy normal map (tangents given on the
/// plane, left to the loader on the cube) and a metallic-roughness map; a point and a spot light.
pub fn textured() -> Vec<u8> {
    let mut g = Gltf::new();
    let checker = g.png_image("checker", 128, 128, &checker_texels());
    let bumps = g.png_image("bumps", 128, 128, &bump_normal_texels());
    let metal_rough = g.png_image("metal-rough", 64, 64, &metal_rough_texels());
    let smooth =
        g.push("samplers", json!({ "magFilter": 9729, "minFilter": 9987, "wrapS": 10497, "wrapT": 10497 }));
    let pixelated =
        g.push("samplers", json!({ "magFilter": 9728, "minFilter": 9729, "wrapS": 33648, "wrapT": 33071 }));
    let checker_pixelated = g.push("textures", json!({ "source": checker, "sampler": pixelated }));
    let bumps = g.push("textures", json!({ "source": bumps, "sampler": smooth }));
    let metal_rough = g.push("textures", json!({ "source": metal_rough, "sampler": smooth }));
    let checker_smooth = g.push("textures", json!({ "source": checker, "sampler": smooth }));
    let floor_material = g.push(
        "materials",
        json!({
            "name": "floor",
            "pbrMetallicRoughness": {
                "baseColorTexture": { "index": checker_pixelated, "extensions": { "KHR_texture_transform": {
                    "offset": [0.5, 0.25], "rotation": 0.3, "scale": [4.0, 4.0] } } },
                "metallicRoughnessTexture": { "index": metal_rough }
            },
            "normalTexture": { "index": bumps }
        }),
    );
    let cube_material = g.push("materials", json!({
        "name": "cube",
        "pbrMetallicRoughness": { "baseColorTexture": { "index": checker_smooth }, "metallicFactor": 0.0 },
        "normalTexture": { "index": bumps, "scale": 0.5, "extensions": { "KHR_texture_transform": { "scale": [2.0, 2.0] } } }
    }));
    let mut plane = Mesh::default();
    plane.quad(Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 0.0, -2.0));
    let plane = vec![g.primitive(&plane, floor_material)];
    let plane = g.mesh("plane", plane);
    let mut cube = Mesh::cuboid();
    cube.tangents.clear();
    let cube = vec![g.primitive(&cube, cube_material)];
    let cube = g.mesh("cube", cube);
    let point = g.light(json!({ "name": "bulb", "type": "point", "color": [1.0, 0.9, 0.8], "intensity": 20.0, "range": 10.0 }));
    let spot = g.light(json!({ "name": "spot", "type": "spot", "intensity": 50.0,
        "spot": { "innerConeAngle": 0.2, "outerConeAngle": 0.5 } }));
    let nodes = vec![
        g.push("nodes", json!({ "name": "plane", "mesh": plane })),
        g.push("nodes", json!({ "name": "cube", "mesh": cube, "translation": [0.0, 0.5, 0.0], "rotation": y_rotation(30.0) })),
        g.push("nodes", json!({ "name": "bulb", "translation": [1.0, 2.0, 1.0], "extensions": { "KHR_lights_punctual": { "light": point } } })),
        g.push("nodes", json!({ "name": "spot", "translation": [0.0, 3.0, 0.0],
            "rotation": quat(Quat::from_rotation_arc(-Vec3::Z, -Vec3::Y)), "extensions": { "KHR_lights_punctual": { "light": spot } } })),
        g.camera_node("camera", [2.5, 2.0, 3.5], look_rotation(Vec3::new(2.5, 2.0, 3.5), Vec3::new(0.0, 0.3, 0.0)), 0.8, 4.0 / 3.0),
    ];
    g.finish(nodes, &["KHR_texture_transform", "KHR_lights_punctual"])
}

/// Many lights over a hall of pillars, for light selection (ReSTIR DI against power sampling,
/// issue 22): a 16 m square floor and a back wall, a 4×4 grid of pillars, 240 small emissive
/// tiles (480 triangles, facing down, 0.2 m a side, 12 materials whose radiance spans 0.2 to 40)
/// scattered between 0.4 and 3 m up, and 128 point and 8 spot lights (intensity 0.04 to 4 cd,
/// coloured) among them; a camera looking down the hall. Positions, colours and strengths come
/// from a fixed linear congruential sequence, so the file is the same on every machine.
pub fn many_lights() -> Vec<u8> {
    let mut g = Gltf::new();
    // Numerical Recipes' LCG, top 24 bits as a float in [0, 1).
    let mut state = 0x2545_f491u32;
    let mut rand = move || {
        state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (state >> 8) as f32 / 16_777_216.0
    };
    let palette = [[1.0, 0.55, 0.25], [0.35, 0.6, 1.0], [1.0, 0.9, 0.8], [0.5, 1.0, 0.45]];
    let floor_material = g.material("floor", [0.6, 0.6, 0.6], 0.0, 0.7);
    let pillar_material = g.material("pillar", [0.8, 0.78, 0.75], 0.0, 0.5);
    let c = Vec3::new;
    let mut hall = Mesh::default();
    hall.quad(c(0.0, 0.0, 0.0), c(8.0, 0.0, 0.0), c(0.0, 0.0, -8.0)); // floor, +Y
    hall.quad(c(0.0, 2.0, -8.0), c(8.0, 0.0, 0.0), c(0.0, 2.0, 0.0)); // back wall, +Z
    let hall = vec![g.primitive(&hall.bare(), floor_material)];
    let hall = g.mesh("hall", hall);
    let pillar = vec![g.primitive(&Mesh::cuboid().bare(), pillar_material)];
    let pillar = g.mesh("pillar", pillar);
    let mut nodes = vec![g.push("nodes", json!({ "name": "hall", "mesh": hall }))];
    for i in 0..16 {
        let (x, z) = ((i % 4) as f64 * 4.0 - 6.0, (i / 4) as f64 * 4.0 - 6.0);
        nodes.push(g.push(
            "nodes",
            json!({ "name": format!("pillar {i}"), "mesh": pillar,
            "translation": [x, 1.5, z], "scale": [0.3, 1.5, 0.3] }),
        ));
    }
    // 12 emissive materials: four colours, three strengths each; 20 tiles per material.
    let mut tiles = Vec::new();
    for m in 0..12 {
        let colour = palette[m % 4];
        let strength = [0.2, 3.0, 40.0][m / 4];
        let material = g.push("materials", json!({
            "name": format!("lamp {m}"),
            "pbrMetallicRoughness": { "baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0 },
            "emissiveFactor": colour,
            "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": strength } }
        }));
        let mut mesh = Mesh::default();
        for _ in 0..20 {
            let p = c(rand() * 15.0 - 7.5, 0.4 + rand() * 2.6, rand() * 15.0 - 7.5);
            mesh.quad(p, c(0.1, 0.0, 0.0), c(0.0, 0.0, 0.1)); // facing -Y
        }
        tiles.push(g.primitive(&mesh.bare(), material));
    }
    let tiles = g.mesh("lamps", tiles);
    nodes.push(g.push("nodes", json!({ "name": "lamps", "mesh": tiles })));
    for i in 0..136 {
        let colour = palette[i % 4];
        let intensity = 0.04 * 100f32.powf(rand());
        let position = [rand() * 15.0 - 7.5, 0.2 + rand() * 2.8, rand() * 15.0 - 7.5];
        let (light, rotation) = if i < 128 {
            (
                json!({ "name": format!("bulb {i}"), "type": "point", "color": colour, "intensity": intensity }),
                None,
            )
        } else {
            let light = json!({ "name": format!("spot {i}"), "type": "spot", "color": colour,
                "intensity": intensity * 10.0, "spot": { "innerConeAngle": 0.3, "outerConeAngle": 0.6 } });
            let down = c(rand() - 0.5, -1.0, rand() - 0.5).normalize();
            (light, Some(quat(Quat::from_rotation_arc(-Vec3::Z, down))))
        };
        let light = g.light(light);
        let mut node = json!({ "name": format!("light {i}"), "translation": position,
            "extensions": { "KHR_lights_punctual": { "light": light } } });
        if let Some(rotation) = rotation {
            node["rotation"] = rotation;
        }
        nodes.push(g.push("nodes", node));
    }
    let eye = Vec3::new(0.0, 4.5, 9.5);
    nodes.push(g.camera_node(
        "camera",
        [0.0, 4.5, 9.5],
        look_rotation(eye, Vec3::new(0.0, 0.5, 0.0)),
        0.9,
        1.0,
    ));
    g.finish(nodes, &["KHR_materials_emissive_strength", "KHR_lights_punctual"])
}

/// Rough glass in a corner of checkered floor and wall: a solid sphere (`KHR_materials_volume`,
/// `KHR_materials_ior` 1.5, roughness 0.3) and a thin-walled, slightly blue pane (roughness 0.2),
/// both `KHR_materials_transmission` 1, hovering above the floor; no light of its own. Made for
/// the sky of tests/reference/sky-128x64.exr: the whole corner is turned so that its sun (56 % of
/// the sky's power in one texel, 7° high) stands straight behind the 2 m wall, which shades every
/// surface from it. Neither glass then focuses the sun on anything a camera path can reach, a
/// caustic that only BSDF sampling could find, rarely (tests/mitsuba_reference.rs); a point light
/// seen through the glass (next-event estimation through a rough refraction) would be 20 times
/// as noisy as the sky.
pub fn glass() -> Vec<u8> {
    let mut g = Gltf::new();
    let checker = g.png_image("checker", 128, 128, &checker_texels());
    let nearest =
        g.push("samplers", json!({ "magFilter": 9728, "minFilter": 9728, "wrapS": 10497, "wrapT": 10497 }));
    let checker = g.push("textures", json!({ "source": checker, "sampler": nearest }));
    let checkered = |g: &mut Gltf, name: &str, color: [f64; 3], scale: [f64; 2]| {
        g.push("materials", json!({ "name": name, "pbrMetallicRoughness": {
            "baseColorFactor": [color[0], color[1], color[2], 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.9,
            "baseColorTexture": { "index": checker, "extensions": { "KHR_texture_transform": { "scale": scale } } } } }))
    };
    let floor_material = checkered(&mut g, "floor", [1.0, 1.0, 1.0], [2.0, 2.0]);
    let wall_material = checkered(&mut g, "wall", [1.0, 0.85, 0.7], [2.0, 1.5]);
    let solid = g.push("materials", json!({
        "name": "solid rough glass",
        "pbrMetallicRoughness": { "baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.3 },
        "extensions": {
            "KHR_materials_transmission": { "transmissionFactor": 1.0 },
            "KHR_materials_volume": { "thicknessFactor": 0.7 },
            "KHR_materials_ior": { "ior": 1.5 }
        }
    }));
    let thin = g.push("materials", json!({
        "name": "thin rough glass",
        "pbrMetallicRoughness": { "baseColorFactor": [0.8, 0.9, 1.0, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.2 },
        "doubleSided": true,
        "extensions": { "KHR_materials_transmission": { "transmissionFactor": 1.0 } }
    }));
    let mut floor = Mesh::default();
    floor.quad(Vec3::new(0.0, 0.0, 0.1), Vec3::new(1.3, 0.0, 0.0), Vec3::new(0.0, 0.0, -1.1));
    floor.tangents.clear();
    let floor = vec![g.primitive(&floor, floor_material)];
    let floor = g.mesh("floor", floor);
    let mut wall = Mesh::default();
    wall.quad(Vec3::new(0.0, 1.0, -1.0), Vec3::new(1.5, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0));
    wall.tangents.clear();
    let wall = vec![g.primitive(&wall, wall_material)];
    let wall = g.mesh("wall", wall);
    let sphere = vec![g.primitive(&Mesh::uv_sphere(0.35, 48, 24), solid)];
    let sphere = g.mesh("glass sphere", sphere);
    let mut pane = Mesh::default();
    pane.quad(Vec3::ZERO, Vec3::new(0.35, 0.0, 0.0), Vec3::new(0.0, 0.4, 0.0));
    let pane = vec![g.primitive(&pane.bare(), thin)];
    let pane = g.mesh("glass pane", pane);
    let children = vec![
        g.push("nodes", json!({ "name": "floor", "mesh": floor })),
        g.push("nodes", json!({ "name": "wall", "mesh": wall })),
        g.push("nodes", json!({ "name": "glass sphere", "mesh": sphere, "translation": [-0.45, 0.6, -0.15] })),
        g.push("nodes", json!({ "name": "glass pane", "mesh": pane, "translation": [0.5, 0.6, 0.25], "rotation": y_rotation(25.0) })),
        g.camera_node("camera", [0.0, 1.25, 2.7], look_rotation(Vec3::new(0.0, 1.25, 2.7), Vec3::new(0.0, 0.5, -0.3)), 0.75, 4.0 / 3.0),
    ];
    // The sun of sky-128x64.exr lies along (0.57, 0.12, -0.81): the corner's -Z turned onto it.
    let corner =
        g.push("nodes", json!({ "name": "corner", "rotation": y_rotation(-35.0), "children": children }));
    g.finish(
        vec![corner],
        &["KHR_texture_transform", "KHR_materials_transmission", "KHR_materials_volume", "KHR_materials_ior"],
    )
}

/// Animation for `--time` / `--frames` and the embedding API's re-posing (one 2-second loop):
/// a skinned tube bending at its elbow (two joints, weights blended over the middle fifth),
/// a tilted roller turning on a turntable node (rigid: its child keeps the tilt), and a sphere squashing by a morph target; on a floor, lit
/// by a sun and a point light. Three animations: "bend" (the elbow, LINEAR rotations: slerp),
/// "turn" (the turntable, LINEAR quaternions), "squash" (the morph weight, CUBICSPLINE).
pub fn animated() -> Vec<u8> {
    let mut g = Gltf::new();
    let floor_material = g.material("floor", [0.6, 0.6, 0.6], 0.0, 0.8);
    let arm_material = g.material("arm", [0.8, 0.3, 0.2], 0.0, 0.5);
    let roller_material = g.material("roller", [0.2, 0.4, 0.8], 0.5, 0.3);
    let ball_material = g.material("ball", [0.9, 0.8, 0.3], 0.0, 0.4);
    let mut floor = Mesh::default();
    floor.quad(Vec3::ZERO, Vec3::new(3.0, 0.0, 0.0), Vec3::new(0.0, 0.0, -3.0));
    let floor = vec![g.primitive(&floor.bare(), floor_material)];
    let floor = g.mesh("floor", floor);

    // The tube: radius 0.15, 1.6 m up from (-1, 0, 0), in mesh space where the skin binds it.
    let tube = Mesh::tube(Vec3::new(-1.0, 0.0, 0.0), 0.15, 1.6, 32, 40);
    // Joint 1 (the elbow, at 0.8 m) takes over between 0.64 and 0.96 m.
    let joints: Vec<[u8; 4]> = vec![[0, 1, 0, 0]; tube.positions.len()];
    let weights: Vec<[f32; 4]> = tube
        .positions
        .iter()
        .map(|p| {
            let w = ((p[1] - 0.64) / 0.32).clamp(0.0, 1.0);
            [1.0 - w, w, 0.0, 0.0]
        })
        .collect();
    let mut arm = g.primitive(&tube.bare(), arm_material);
    let joints_bytes: Vec<u8> = joints.iter().flatten().copied().collect();
    let view = g.view(&joints_bytes, Some(34962));
    arm["attributes"]["JOINTS_0"] = json!(g.push(
        "accessors",
        json!({ "bufferView": view, "componentType": 5121, "count": joints.len(), "type": "VEC4" })
    ));
    arm["attributes"]["WEIGHTS_0"] = json!(g.floats(&weights, false));
    let arm = g.mesh("arm", vec![arm]);
    let inverse_bind: Vec<u8> = [Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, -0.8, 0.0)]
        .iter()
        .flat_map(|t| glam::Mat4::from_translation(*t).to_cols_array())
        .flat_map(f32::to_le_bytes)
        .collect();
    let view = g.view(&inverse_bind, None);
    let inverse_bind =
        g.push("accessors", json!({ "bufferView": view, "componentType": 5126, "count": 2, "type": "MAT4" }));

    let roller =
        vec![g.primitive(&Mesh::tube(Vec3::new(0.0, -0.5, 0.0), 0.12, 1.0, 32, 40), roller_material)];
    let roller = g.mesh("roller", roller);

    // The ball: a UV sphere with one morph target that squashes it (y × 0.5, x and z × 1.25).
    let sphere = Mesh::uv_sphere(0.3, 40, 20);
    let mut ball = g.primitive(&sphere, ball_material);
    let squash: Vec<[f32; 3]> =
        sphere.positions.iter().map(|p| [p[0] * 0.25, -p[1] * 0.5, p[2] * 0.25]).collect();
    ball["targets"] = json!([{ "POSITION": g.floats(&squash, true) }]);
    let ball = g.push("meshes", json!({ "name": "ball", "primitives": [ball], "weights": [0.0] }));

    let nodes = [
        json!({ "name": "floor", "mesh": floor }),
        json!({ "name": "arm", "mesh": arm, "skin": 0 }),
        json!({ "name": "shoulder", "translation": [-1.0, 0.0, 0.0], "children": [3] }),
        json!({ "name": "elbow", "translation": [0.0, 0.8, 0.0] }),
        json!({ "name": "turntable", "translation": [1.1, 0.35, -0.3], "children": [6] }),
        json!({ "name": "ball", "mesh": ball, "translation": [0.1, 0.3, 0.8] }),
        json!({ "name": "roller", "mesh": roller, "rotation": quat(Quat::from_rotation_z(1.2)) }),
    ];
    for node in nodes {
        g.push("nodes", node);
    }
    g.push(
        "skins",
        json!({ "name": "arm", "joints": [2, 3], "skeleton": 2, "inverseBindMatrices": inverse_bind }),
    );
    let sun =
        g.light(json!({ "name": "sun", "type": "directional", "color": [1.0, 0.96, 0.9], "intensity": 2.5 }));
    let sun = g.push(
        "nodes",
        json!({ "name": "sun", "extensions": { "KHR_lights_punctual": { "light": sun } },
        "rotation": quat(Quat::from_rotation_y(0.6) * Quat::from_rotation_x(-0.9)) }),
    );
    let bulb =
        g.light(json!({ "name": "bulb", "type": "point", "color": [1.0, 0.85, 0.7], "intensity": 6.0 }));
    let bulb = g.push(
        "nodes",
        json!({ "name": "bulb", "translation": [0.0, 2.2, 1.0],
        "extensions": { "KHR_lights_punctual": { "light": bulb } } }),
    );
    let camera = g.camera_node(
        "camera",
        [0.0, 1.6, 4.2],
        look_rotation(Vec3::new(0.0, 1.6, 4.2), Vec3::new(0.0, 0.6, 0.0)),
        0.7,
        4.0 / 3.0,
    );

    // Times and values of each animation's sampler.
    let times = |g: &mut Gltf, t: &[f32]| {
        let data: Vec<[f32; 1]> = t.iter().map(|&t| [t]).collect();
        g.floats(&data, true)
    };
    // "bend" and "turn" share their key times: rotations about an axis, in degrees, per key.
    let keys = times(&mut g, &[0.0, 0.5, 1.0, 1.5, 2.0]);
    let rotations = |g: &mut Gltf, about: fn(f32) -> Quat, degrees: [f32; 5]| {
        let q: Vec<[f32; 4]> = degrees.iter().map(|d| about(d.to_radians()).to_array()).collect();
        g.floats(&q, false)
    };
    let bend = rotations(&mut g, Quat::from_rotation_z, [0.0, 50.0, 80.0, 50.0, 0.0]);
    let turn = rotations(&mut g, Quat::from_rotation_y, [0.0, 80.0, 160.0, 80.0, 0.0]);
    // CUBICSPLINE: in-tangent, value, out-tangent per key (weights 0, 1, 0 at 0, 1, 2 s).
    let squash_in = times(&mut g, &[0.0, 1.0, 2.0]);
    let squash: Vec<[f32; 1]> = [[0.0], [0.0], [1.5], [0.0], [1.0], [0.0], [-1.5], [0.0], [0.0]].to_vec();
    let squash = g.floats(&squash, false);
    let animation = |name: &str,
                     input: usize,
                     output: usize,
                     interpolation: &str,
                     node: usize,
                     path: &str| {
        json!({ "name": name, "samplers": [{ "input": input, "output": output, "interpolation": interpolation }],
            "channels": [{ "sampler": 0, "target": { "node": node, "path": path } }] })
    };
    g.push("animations", animation("bend", keys, bend, "LINEAR", 3, "rotation"));
    g.push("animations", animation("turn", keys, turn, "LINEAR", 4, "rotation"));
    g.push("animations", animation("squash", squash_in, squash, "CUBICSPLINE", 5, "weights"));
    g.finish(vec![0, 1, 2, 4, 5, sun, bulb, camera], &["KHR_lights_punctual"])
}

/// A rough white 2 m square facing the camera (+Z) and filling its view, for the occlusion-map
/// tests (tests/occlusion_map.rs; not in `scenes/`). With `occlusion: Some(strength)` it has an
/// occlusion map that is black on its left half and white on its right (16 × 16, nearest); every
/// variant has a 1 × 1 white base colour texture, so all of them run the same specialised
/// kernels. With `sun`, a directional light shines on it straight on.
pub fn occlusion_square(occlusion: Option<f64>, sun: bool) -> Vec<u8> {
    let mut g = Gltf::new();
    let nearest = g.push("samplers", json!({ "magFilter": 9728, "minFilter": 9728 }));
    let white = g.png_image("white", 1, 1, &[255, 255, 255]);
    let white = g.push("textures", json!({ "source": white, "sampler": nearest }));
    let mut material = json!({
        "name": "square",
        "pbrMetallicRoughness": { "baseColorFactor": [0.8, 0.8, 0.8, 1.0], "baseColorTexture": { "index": white },
            "metallicFactor": 0.0, "roughnessFactor": 0.7 }
    });
    if let Some(strength) = occlusion {
        let halves =
            g.png_image("halves", 16, 16, &texels(16, 16, |x, _| if x < 8 { [0; 3] } else { [255; 3] }));
        let halves = g.push("textures", json!({ "source": halves, "sampler": nearest }));
        material["occlusionTexture"] = json!({ "index": halves, "strength": strength });
    }
    let material = g.push("materials", material);
    let mut nodes = square_in_view(&mut g, material);
    let mut extensions = Vec::new();
    if sun {
        let light = g.light(json!({ "name": "sun", "type": "directional", "intensity": 2.0 }));
        // A directional light shines along its node's -Z: straight at the square.
        nodes.push(g.push(
            "nodes",
            json!({ "name": "sun", "extensions": { "KHR_lights_punctual": { "light": light } } }),
        ));
        extensions.push("KHR_lights_punctual");
    }
    g.finish(nodes, &extensions)
}

/// A 2 m square at the origin facing +Z, made of `material`, and a camera 2 m away on +Z that
/// sees ±0.8 m of it; returns the two nodes.
fn square_in_view(g: &mut Gltf, material: usize) -> Vec<usize> {
    let mut square = Mesh::default();
    square.quad(Vec3::ZERO, Vec3::X, Vec3::Y);
    let square = vec![g.primitive(&square, material)];
    let square = g.mesh("square", square);
    vec![
        g.push("nodes", json!({ "name": "square", "mesh": square })),
        g.camera_node("camera", [0.0, 0.0, 2.0], json!([0.0, 0.0, 0.0, 1.0]), 2.0 * 0.4f64.atan(), 1.0),
    ]
}

/// A square of side `2 half` at the origin facing +Z for the parallax tests (tests/parallax.rs; not
/// in `scenes/`): white, rough, dielectric, UV (0, 0) at its corner (-half, +half), u along +X and
/// v along -Y, with TEXCOORD_1 equal to TEXCOORD_0 (the G-buffer stores UV set 1 at the point
/// parallax occlusion mapping found). Its material has the `width` × `height` height map
/// `heights` (one byte per texel, rows from the top; nearest filtering unless `linear`) and, with
/// `parallax: Some(p)`, `"extensions": {"UMBRA_implicit": {"parallax": p}}`, where `p` refers to
/// the height map as texture 0. No camera and no light: the tests set their own.
pub fn parallax_square(
    half: f32,
    width: u32,
    height: u32,
    heights: &[u8],
    linear: bool,
    parallax: Option<Value>,
) -> Vec<u8> {
    let mut g = Gltf::new();
    let filter = if linear { 9729 } else { 9728 };
    let sampler = g.push("samplers", json!({ "magFilter": filter, "minFilter": filter }));
    let rgb: Vec<u8> = heights.iter().flat_map(|&h| [h, h, h]).collect();
    let image = g.png_image("height", width, height, &rgb);
    let texture = g.push("textures", json!({ "source": image, "sampler": sampler }));
    assert_eq!(texture, 0);
    let mut material = json!({
        "name": "pom",
        "pbrMetallicRoughness": { "baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0 }
    });
    let mut extensions = Vec::new();
    if let Some(p) = parallax {
        material["extensions"] = json!({ "UMBRA_implicit": { "parallax": p } });
        extensions.push("UMBRA_implicit");
    }
    let material = g.push("materials", material);
    let mut square = Mesh::default();
    square.quad(Vec3::ZERO, Vec3::X * half, Vec3::Y * half);
    let geometry = g.geometry(&square);
    let mut primitive = geometry.with_material(material);
    primitive["attributes"]["TEXCOORD_1"] = primitive["attributes"]["TEXCOORD_0"].clone();
    let mesh = g.mesh("square", vec![primitive]);
    let node = g.push("nodes", json!({ "name": "square", "mesh": mesh }));
    g.finish(vec![node], &extensions)
}

/// A black square filling the view (`square_in_view`; tests/gltf_textures.rs) that emits its
/// 2 × 2 emissive texture (RGB `texels`, rows from the top, nearest filtering) × `factor` ×
/// `KHR_materials_emissive_strength` `strength`; no light.
pub fn emissive_square(texels: &[u8], factor: [f64; 3], strength: f64) -> Vec<u8> {
    let mut g = Gltf::new();
    let nearest = g.push("samplers", json!({ "magFilter": 9728, "minFilter": 9728 }));
    let image = g.png_image("emission", 2, 2, texels);
    let texture = g.push("textures", json!({ "source": image, "sampler": nearest }));
    let material = g.push(
        "materials",
        json!({
            "name": "glow",
            "pbrMetallicRoughness": { "baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0 },
            "emissiveTexture": { "index": texture },
            "emissiveFactor": factor,
            "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": strength } }
        }),
    );
    let nodes = square_in_view(&mut g, material);
    g.finish(nodes, &["KHR_materials_emissive_strength"])
}

/// A square filling the view (`square_in_view`; tests/gltf_textures.rs) whose base colour
/// texture (2 × 2 RGB, rows from the top, nearest) is the lossless WebP of `webp` through
/// `EXT_texture_webp`, with the PNG of `fallback` as its plain `source`; without a fallback the
/// texture has no `source` and the extension is required.
pub fn webp_square(webp: &[u8], fallback: Option<&[u8]>) -> Vec<u8> {
    let mut g = Gltf::new();
    let nearest = g.push("samplers", json!({ "magFilter": 9728, "minFilter": 9728 }));
    let webp = g.webp_image("lossless", 2, 2, webp);
    let mut texture = json!({ "sampler": nearest, "extensions": { "EXT_texture_webp": { "source": webp } } });
    if let Some(fallback) = fallback {
        texture["source"] = json!(g.png_image("fallback", 2, 2, fallback));
    }
    let texture = g.push("textures", texture);
    let material = g.push(
        "materials",
        json!({ "name": "webp", "pbrMetallicRoughness": { "baseColorTexture": { "index": texture }, "metallicFactor": 0.0 } }),
    );
    let nodes = square_in_view(&mut g, material);
    let mut glb = g.finish(nodes, &["EXT_texture_webp"]);
    if fallback.is_none() {
        let (mut json, bin) = split_glb(&glb);
        json["extensionsRequired"] = json!(["EXT_texture_webp"]);
        glb = self::glb(&serde_json::to_vec(&json).expect("JSON"), &bin);
    }
    glb
}

/// One wedge mesh placed by twelve nodes: a rotated ring of eight, a nested arm (translation,
/// uniform scale, rotation, and a `matrix` node), a mirrored node (scale -1 in x) with a child.
/// A second scene, not the default, holds one more node that must not be loaded.
pub fn instanced() -> Vec<u8> {
    let mut g = Gltf::new();
    let material = g.material("wedge", [0.8, 0.8, 0.8], 0.0, 0.5);
    let wedge = vec![g.primitive(&Mesh::wedge(), material)];
    let wedge = g.mesh("wedge", wedge);
    // Node indices are fixed up front so parents can name their children.
    let ring: Vec<usize> = (1..=8).collect();
    let mut nodes = vec![
        json!({ "name": "ring", "rotation": y_rotation(30.0), "children": ring.iter().copied().chain([9]).collect::<Vec<_>>() }),
    ];
    for k in 0..8 {
        let angle = k as f64 * std::f64::consts::TAU / 8.0;
        nodes.push(json!({ "name": format!("ring {k}"), "mesh": wedge, "scale": [0.5, 0.5, 0.5],
            "translation": [2.0 * angle.cos(), 0.0, 2.0 * angle.sin()] }));
    }
    nodes.push(
        json!({ "name": "arm", "translation": [0.0, 1.0, 0.0], "scale": [2.0, 2.0, 2.0], "children": [10] }),
    );
    nodes.push(json!({ "name": "hand", "mesh": wedge, "translation": [0.0, 0.5, 0.0], "rotation": x_rotation(45.0), "children": [11] }));
    nodes.push(json!({ "name": "finger", "mesh": wedge,
        "matrix": [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.5, 0.0, 0.0, 1.0] }));
    nodes.push(json!({ "name": "mirror", "mesh": wedge, "translation": [-3.0, 0.0, 0.0], "scale": [-1.0, 1.0, 1.0], "children": [13] }));
    nodes.push(json!({ "name": "mirror child", "mesh": wedge, "translation": [0.0, 1.0, 0.0] }));
    nodes.push(json!({ "name": "not in the default scene", "mesh": wedge, "translation": [0.0, -5.0, 0.0] }));
    for node in nodes {
        g.push("nodes", node);
    }
    let camera = g.camera_node(
        "camera",
        [0.0, 4.0, 9.0],
        look_rotation(Vec3::new(0.0, 4.0, 9.0), Vec3::new(-0.5, 0.5, 0.0)),
        0.8,
        1.5,
    );
    g.root.insert(
        "scenes".into(),
        json!([{ "name": "main", "nodes": [0, 12, camera] }, { "name": "other", "nodes": [14] }]),
    );
    g.finish_with_scenes(&[])
}

// ---------------------------------------------------------------------------------------------
// Geometry

/// Triangles with per-vertex normal, UV and tangent, wound counter-clockwise around the normals.
#[derive(Default)]
pub struct Mesh {
    pub positions: Vec<[f32; 3]>,
    pub normals: Vec<[f32; 3]>,
    pub uvs: Vec<[f32; 2]>,
    /// Empty, or one per vertex.
    pub tangents: Vec<[f32; 4]>,
    pub indices: Vec<u32>,
}

impl Mesh {
    /// The quad `center ± u ± v`, facing `u × v`; UV (0,0) at `center - u + v` (the image's
    /// top-left) and the tangent along `u`.
    pub fn quad(&mut self, center: Vec3, u: Vec3, v: Vec3) {
        let normal = u.cross(v).normalize();
        let base = self.positions.len() as u32;
        for (corner, uv) in
            [(-u - v, [0.0, 1.0]), (u - v, [1.0, 1.0]), (u + v, [1.0, 0.0]), (-u + v, [0.0, 0.0])]
        {
            self.positions.push((center + corner).to_array());
            self.normals.push(normal.to_array());
            self.uvs.push(uv);
            self.tangents.push(u.normalize().extend(1.0).to_array());
        }
        self.indices.extend([base, base + 1, base + 2, base, base + 2, base + 3]);
    }

    /// A convex polygon with a flat normal, fan-triangulated and wound around `outward`.
    fn polygon(&mut self, corners: &[Vec3], outward: Vec3) {
        let normal = (corners[1] - corners[0]).cross(corners[2] - corners[0]).normalize();
        let flip = normal.dot(outward) < 0.0;
        let base = self.positions.len() as u32;
        for &p in corners {
            self.positions.push(p.to_array());
            self.normals.push(if flip { -normal } else { normal }.to_array());
            self.uvs.push([0.0, 0.0]);
            self.tangents.push([1.0, 0.0, 0.0, 1.0]);
        }
        for i in 1..corners.len() as u32 - 1 {
            let (b, c) = if flip { (i + 1, i) } else { (i, i + 1) };
            self.indices.extend([base, base + b, base + c]);
        }
    }

    /// The unit cube centred on the origin, six quads facing out.
    pub fn cuboid() -> Self {
        let mut mesh = Mesh::default();
        for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
            for normal in [axis, -axis] {
                let up = if axis == Vec3::Y { Vec3::Z } else { Vec3::Y };
                mesh.quad(normal * 0.5, up.cross(normal) * 0.5, up * 0.5);
            }
        }
        mesh
    }

    /// A wedge: the right triangle (0,0) (1,0) (0,1) in x-y, extruded over z in [-0.25, 0.25].
    pub fn wedge() -> Self {
        let mut mesh = Mesh::default();
        let (front, back) = (0.25, -0.25);
        let p = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
        mesh.polygon(&[p(0.0, 0.0, front), p(1.0, 0.0, front), p(0.0, 1.0, front)], Vec3::Z);
        mesh.polygon(&[p(0.0, 0.0, back), p(1.0, 0.0, back), p(0.0, 1.0, back)], -Vec3::Z);
        mesh.polygon(
            &[p(0.0, 0.0, back), p(1.0, 0.0, back), p(1.0, 0.0, front), p(0.0, 0.0, front)],
            -Vec3::Y,
        );
        mesh.polygon(
            &[p(0.0, 0.0, back), p(0.0, 1.0, back), p(0.0, 1.0, front), p(0.0, 0.0, front)],
            -Vec3::X,
        );
        mesh.polygon(
            &[p(1.0, 0.0, back), p(0.0, 1.0, back), p(0.0, 1.0, front), p(1.0, 0.0, front)],
            Vec3::new(1.0, 1.0, 0.0),
        );
        mesh.bare()
    }

    /// A UV sphere of `radius`: `segments` around, `rings` from pole to pole, a seam of
    /// duplicated vertices at u = 0 / 1.
    pub fn uv_sphere(radius: f32, segments: u32, rings: u32) -> Self {
        let mut mesh = Mesh::default();
        for r in 0..=rings {
            let theta = std::f64::consts::PI * r as f64 / rings as f64;
            for s in 0..=segments {
                let phi = std::f64::consts::TAU * s as f64 / segments as f64;
                let n = Vec3::new(
                    (theta.sin() * phi.cos()) as f32,
                    theta.cos() as f32,
                    (-theta.sin() * phi.sin()) as f32,
                );
                mesh.positions.push((n * radius).to_array());
                mesh.normals.push(n.to_array());
                mesh.uvs.push([s as f32 / segments as f32, r as f32 / rings as f32]);
            }
        }
        let row = segments + 1;
        for r in 0..rings {
            for s in 0..segments {
                let (a, b) = (r * row + s, (r + 1) * row + s);
                if r != 0 {
                    mesh.indices.extend([a, b, a + 1]);
                }
                if r != rings - 1 {
                    mesh.indices.extend([a + 1, b, b + 1]);
                }
            }
        }
        mesh.uvs.clear();
        mesh
    }

    /// An open tube of `radius` standing `height` up +Y from `base`: `segments` around, `rings`
    /// along, normals out (no UVs, no caps).
    pub fn tube(base: Vec3, radius: f32, height: f32, segments: u32, rings: u32) -> Self {
        let mut mesh = Mesh::default();
        for r in 0..=rings {
            let y = height * r as f32 / rings as f32;
            for s in 0..=segments {
                let phi = std::f32::consts::TAU * s as f32 / segments as f32;
                let n = Vec3::new(phi.cos(), 0.0, -phi.sin());
                mesh.positions.push((base + Vec3::new(0.0, y, 0.0) + n * radius).to_array());
                mesh.normals.push(n.to_array());
            }
        }
        let row = segments + 1;
        for r in 0..rings {
            for s in 0..segments {
                let (a, b) = (r * row + s, (r + 1) * row + s);
                mesh.indices.extend([a, a + 1, b, a + 1, b + 1, b]);
            }
        }
        mesh
    }

    /// The same mesh without UVs and tangents.
    fn bare(mut self) -> Self {
        self.uvs.clear();
        self.tangents.clear();
        self
    }

    /// Panics unless every triangle's winding agrees with its vertices' normals.
    fn check_winding(&self) {
        for t in self.indices.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| Vec3::from(self.positions[i as usize]));
            let n: Vec3 = t.iter().map(|&i| Vec3::from(self.normals[i as usize])).sum();
            assert!((b - a).cross(c - a).dot(n) > 0.0, "generator bug: triangle {t:?} is wound clockwise");
        }
    }
}

/// A rotation of `degrees` about +Y as a glTF quaternion [x, y, z, w].
fn y_rotation(degrees: f64) -> Value {
    let half = degrees.to_radians() / 2.0;
    json!([0.0, half.sin(), 0.0, half.cos()])
}

/// A rotation of `degrees` about +X as a glTF quaternion.
fn x_rotation(degrees: f64) -> Value {
    let half = degrees.to_radians() / 2.0;
    json!([half.sin(), 0.0, 0.0, half.cos()])
}

/// The rotation that makes a camera at `eye` (looking down its -Z, +Y up) look at `target`.
fn look_rotation(eye: Vec3, target: Vec3) -> Value {
    let forward = (target - eye).normalize();
    let right = forward.cross(Vec3::Y).normalize();
    let up = right.cross(forward);
    quat(Quat::from_mat3(&Mat3::from_cols(right, up, -forward)))
}

fn quat(q: Quat) -> Value {
    json!(q.to_array().map(f64::from))
}

// ---------------------------------------------------------------------------------------------
// Textures

fn checker_texels() -> Vec<u8> {
    texels(128, 128, |x, y| if (x / 16 + y / 16) % 2 == 0 { [230, 230, 230] } else { [40, 60, 160] })
}

/// A tangent-space normal map of 4×4 round bumps (+X right, +Y up in the image).
fn bump_normal_texels() -> Vec<u8> {
    texels(128, 128, |x, y| {
        let cell = |c: u32| (c % 32) as f32 / 16.0 - 1.0 + 1.0 / 32.0;
        let p = Vec2::new(cell(x), -cell(y));
        let n = if p.length() < 0.8 {
            Vec3::new(p.x, p.y, (0.64 - p.length_squared()).sqrt() * 2.0).normalize()
        } else {
            Vec3::Z
        };
        (n * 0.5 + 0.5).to_array().map(|c| (c * 255.0).round() as u8)
    })
}

/// Roughness (G) rising left to right, metalness (B) in horizontal stripes.
fn metal_rough_texels() -> Vec<u8> {
    texels(64, 64, |x, y| {
        [255, (38.0 + 217.0 * x as f32 / 63.0).round() as u8, if (y / 16) % 2 == 0 { 255 } else { 0 }]
    })
}

fn texels(width: u32, height: u32, texel: impl Fn(u32, u32) -> [u8; 3]) -> Vec<u8> {
    (0..height).flat_map(|y| (0..width).map(move |x| (x, y))).flat_map(|(x, y)| texel(x, y)).collect()
}

// ---------------------------------------------------------------------------------------------
// The document builder

/// A glTF document under construction, with one binary buffer.
pub struct Gltf {
    root: Map<String, Value>,
    bin: Vec<u8>,
    lights: Vec<Value>,
}

/// A primitive's attributes and indices, to be given a material.
pub struct Geometry {
    attributes: Value,
    indices: usize,
}

impl Geometry {
    fn with_material(&self, material: usize) -> Value {
        json!({ "attributes": self.attributes, "indices": self.indices, "material": material })
    }
}

impl Gltf {
    pub fn new() -> Self {
        let mut root = Map::new();
        root.insert(
            "asset".into(),
            json!({ "version": "2.0", "generator": "umbra tests/support/generate.rs" }),
        );
        Self { root, bin: Vec::new(), lights: Vec::new() }
    }

    /// Appends `value` to the top-level array `key`; returns its index.
    pub fn push(&mut self, key: &str, value: Value) -> usize {
        let array = self.root.entry(key).or_insert_with(|| json!([])).as_array_mut().expect("array");
        array.push(value);
        array.len() - 1
    }

    fn material(&mut self, name: &str, color: [f64; 3], metallic: f64, roughness: f64) -> usize {
        self.push("materials", json!({ "name": name, "pbrMetallicRoughness": {
            "baseColorFactor": [color[0], color[1], color[2], 1.0], "metallicFactor": metallic, "roughnessFactor": roughness } }))
    }

    fn mesh(&mut self, name: &str, primitives: Vec<Value>) -> usize {
        self.push("meshes", json!({ "name": name, "primitives": primitives }))
    }

    fn light(&mut self, light: Value) -> usize {
        self.lights.push(light);
        self.lights.len() - 1
    }

    fn camera_node(
        &mut self,
        name: &str,
        position: [f64; 3],
        rotation: Value,
        yfov: f64,
        aspect: f64,
    ) -> usize {
        let camera = self.push(
            "cameras",
            json!({ "name": name, "type": "perspective",
            "perspective": { "yfov": yfov, "aspectRatio": aspect, "znear": 0.01, "zfar": 100.0 } }),
        );
        self.push(
            "nodes",
            json!({ "name": name, "camera": camera, "translation": position, "rotation": rotation }),
        )
    }

    /// Appends `bytes` as a buffer view (4-byte aligned); returns its index.
    fn view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        self.bin.resize(self.bin.len().div_ceil(4) * 4, 0);
        let mut view = json!({ "buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len() });
        if let Some(target) = target {
            view["target"] = json!(target);
        }
        self.bin.extend_from_slice(bytes);
        self.push("bufferViews", view)
    }

    fn floats<const N: usize>(&mut self, data: &[[f32; N]], bounds: bool) -> usize {
        let bytes: Vec<u8> = data.iter().flatten().flat_map(|f| f.to_le_bytes()).collect();
        let view = self.view(&bytes, Some(34962));
        let kind = ["SCALAR", "VEC2", "VEC3", "VEC4"][N - 1];
        let mut accessor =
            json!({ "bufferView": view, "componentType": 5126, "count": data.len(), "type": kind });
        if bounds {
            let fold = |f: fn(f32, f32) -> f32| {
                (0..N).map(|i| f64::from(data.iter().map(|v| v[i]).reduce(f).unwrap())).collect::<Vec<_>>()
            };
            accessor["min"] = json!(fold(f32::min));
            accessor["max"] = json!(fold(f32::max));
        }
        self.push("accessors", accessor)
    }

    fn indices(&mut self, indices: &[u32]) -> usize {
        let short = indices.iter().all(|&i| i < u16::MAX as u32);
        let bytes: Vec<u8> = if short {
            indices.iter().flat_map(|&i| (i as u16).to_le_bytes()).collect()
        } else {
            indices.iter().flat_map(|i| i.to_le_bytes()).collect()
        };
        let view = self.view(&bytes, Some(34963));
        self.push(
            "accessors",
            json!({ "bufferView": view, "componentType": if short { 5123 } else { 5125 },
            "count": indices.len(), "type": "SCALAR" }),
        )
    }

    /// Writes a mesh's vertex data and indices once, to be shared by several primitives.
    fn geometry(&mut self, mesh: &Mesh) -> Geometry {
        mesh.check_winding();
        let mut attributes = json!({ "POSITION": self.floats(&mesh.positions, true), "NORMAL": self.floats(&mesh.normals, false) });
        if !mesh.uvs.is_empty() {
            attributes["TEXCOORD_0"] = json!(self.floats(&mesh.uvs, false));
        }
        if !mesh.tangents.is_empty() {
            attributes["TANGENT"] = json!(self.floats(&mesh.tangents, false));
        }
        Geometry { attributes, indices: self.indices(&mesh.indices) }
    }

    fn primitive(&mut self, mesh: &Mesh, material: usize) -> Value {
        self.geometry(mesh).with_material(material)
    }

    /// Embeds an RGB8 image as PNG; returns the image index.
    fn png_image(&mut self, name: &str, width: u32, height: u32, rgb: &[u8]) -> usize {
        let mut png = Vec::new();
        image::codecs::png::PngEncoder::new(&mut png)
            .write_image(rgb, width, height, image::ExtendedColorType::Rgb8)
            .expect("PNG encoding");
        let view = self.view(&png, None);
        self.push("images", json!({ "name": name, "bufferView": view, "mimeType": "image/png" }))
    }

    /// Embeds an RGB8 image as lossless WebP; returns the image index.
    fn webp_image(&mut self, name: &str, width: u32, height: u32, rgb: &[u8]) -> usize {
        let mut webp = Vec::new();
        image::codecs::webp::WebPEncoder::new_lossless(&mut webp)
            .write_image(rgb, width, height, image::ExtendedColorType::Rgb8)
            .expect("WebP encoding");
        let view = self.view(&webp, None);
        self.push("images", json!({ "name": name, "bufferView": view, "mimeType": "image/webp" }))
    }

    /// One scene (the default) holding `nodes`, then GLB.
    fn finish(mut self, nodes: Vec<usize>, extensions: &[&str]) -> Vec<u8> {
        self.root.insert("scenes".into(), json!([{ "nodes": nodes }]));
        self.finish_with_scenes(extensions)
    }

    /// GLB of the document as built (scene 0 is the default).
    fn finish_with_scenes(mut self, extensions: &[&str]) -> Vec<u8> {
        self.root.insert("scene".into(), json!(0));
        if !self.lights.is_empty() {
            self.root
                .insert("extensions".into(), json!({ "KHR_lights_punctual": { "lights": self.lights } }));
        }
        if !extensions.is_empty() {
            self.root.insert("extensionsUsed".into(), json!(extensions));
        }
        self.bin.resize(self.bin.len().div_ceil(4) * 4, 0);
        self.root.insert("buffers".into(), json!([{ "byteLength": self.bin.len() }]));
        let json = serde_json::to_vec(&Value::Object(self.root)).expect("JSON");
        glb(&json, &self.bin)
    }
}
