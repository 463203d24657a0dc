//! Split-sum image-based lighting: the kernels' tables against f64 references, and the hybrid
//! renderer's IBL against the path tracer.

mod common;

use common::Gpu;
use umbra::gpu::scene::GpuScene;
use umbra::ibl::{lut_entry, lut_reference, LUT_SIZE};
use umbra::passes::ibl::{IblResources, IblSettings};
use umbra::scene::Scene;

fn scene_file(name: &str) -> Scene {
    Scene::load(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name))
        .expect("scene loads")
}

/// The kernel's BRDF table (128² midpoint samples of visible normals and of the cosine
/// hemisphere per entry) equals the f64 Gauss–Legendre reference within 1e-3 in every entry and
/// channel; the reference's own error, estimated by doubling its nodes on a sample of entries,
/// is below 1e-5.
#[test]
fn brdf_lut_matches_cpu_quadrature() {
    let s = LUT_SIZE as usize;
    // The reference's own error: 64 against 128 nodes per axis, at the table's corners and on a
    // sparse grid.
    let mut self_error: f64 = 0.0;
    for j in (0..s).step_by(5).chain([s - 1]) {
        for i in (0..s).step_by(5).chain([s - 1]) {
            let (nv, r) = ((i as f64 + 0.5) / s as f64, (j as f64 + 0.5) / s as f64);
            let (a, b) = (lut_entry(nv, r, 64), lut_entry(nv, r, 128));
            self_error = self_error.max((0..4).map(|c| (a[c] - b[c]).abs()).fold(0.0, f64::max));
        }
    }
    eprintln!("reference: 64 vs 128 nodes differ by at most {self_error:.2e}");
    assert!(self_error < 1e-5, "the reference quadrature has not converged: {self_error:e}");
    let reference = lut_reference(64);

    let gpu = Gpu::new();
    let scene = GpuScene::upload(&gpu, &scene_file("spheres.glb")).unwrap();
    let ibl = IblResources::build(&gpu, &scene, &IblSettings::default()).unwrap();
    let lut: Vec<[f32; 4]> = ibl.lut.read(&gpu).unwrap();
    let mut worst = (0.0f64, 0, 0);
    for (k, (g, r)) in lut.iter().zip(&reference).enumerate() {
        for c in 0..4 {
            let e = (g[c] as f64 - r[c]).abs();
            if e > worst.0 {
                worst = (e, k, c);
            }
        }
    }
    let (e, k, c) = worst;
    eprintln!(
        "GPU LUT vs reference: max |error| {e:.2e} at n·v {:.3}, roughness {:.3}, channel {c} (GPU {:?}, CPU {:?})",
        ((k % s) as f64 + 0.5) / s as f64,
        ((k / s) as f64 + 0.5) / s as f64,
        lut[k],
        reference[k]
    );
    for j in [0, s / 2, s - 1] {
        for i in [0, s / 2, s - 1] {
            eprintln!("  nv {i:2} r {j:2}: {:?}", lut[j * s + i]);
        }
    }
    assert!(e < 1e-3, "GPU BRDF table differs from the reference by {e:e}");
}
