//! EXR layers and PNG encoding.

use umbra::color::{srgb_encode, to_srgb8};
use umbra::output::{read_exr_channels, write_exr, Layer};

#[test]
fn exr_keeps_named_layers_bit_exact() {
    let (w, h) = (7usize, 5usize);
    let color: Vec<f32> = (0..w * h * 4).map(|i| i as f32 * 0.37 - 3.0).collect();
    let albedo: Vec<f32> = (0..w * h * 3).map(|i| (i % 11) as f32 / 10.0).collect();
    let depth: Vec<f32> = (0..w * h).map(|i| 1.0 + i as f32 * 1e-3).collect();
    let path = std::env::temp_dir().join(format!("umbra-layers-{}.exr", std::process::id()));
    write_exr(
        &path,
        w,
        h,
        &[
            Layer { name: "", channels: &["R", "G", "B", "A"], data: &color },
            Layer { name: "albedo", channels: &["R", "G", "B"], data: &albedo },
            Layer { name: "depth", channels: &["Z"], data: &depth },
        ],
    )
    .unwrap();
    let (rw, rh, channels) = read_exr_channels(&path).unwrap();
    std::fs::remove_file(&path).ok();
    assert_eq!((rw, rh), (w, h));
    let get = |name: &str| &channels.iter().find(|c| c.0 == name).unwrap_or_else(|| panic!("{name}")).1;
    for (c, name) in ["R", "G", "B", "A"].iter().enumerate() {
        let expected: Vec<f32> = color.iter().skip(c).step_by(4).copied().collect();
        assert_eq!(get(name), &expected, "{name}");
    }
    let expected_g: Vec<f32> = albedo.iter().skip(1).step_by(3).copied().collect();
    assert_eq!(get("albedo.G"), &expected_g);
    assert_eq!(get("depth.Z"), &depth);
}

#[test]
fn exr_rejects_a_layer_of_the_wrong_size() {
    let path = std::env::temp_dir().join("umbra-never-written.exr");
    let err = write_exr(&path, 4, 4, &[Layer { name: "", channels: &["R"], data: &[0.0; 15] }]).unwrap_err();
    assert!(err.to_string().contains("umbra-never-written.exr"));
}

#[test]
fn srgb_encoding_matches_the_standard() {
    assert_eq!(srgb_encode(0.0), 0.0);
    assert!((srgb_encode(1.0) - 1.0).abs() < 1e-6);
    assert!((srgb_encode(0.5) - 0.735_356_6).abs() < 1e-5);
    // Linear segment below the knee.
    assert!((srgb_encode(0.002) - 0.02584).abs() < 1e-6);
    let px = to_srgb8(&[0.5, f32::NAN, 4.0, 0.25], 1.0);
    assert_eq!(px, vec![188, 0, 255, 64]);
}
