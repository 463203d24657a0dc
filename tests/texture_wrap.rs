//! texture.glsl's wrapping of integer texel coordinates (repeat and mirrored repeat), whose
//! modulo avoids integer division (CPU devices divide one lane at a time): bit-exact against
//! Rust's `rem_euclid` over sizes that are and are not powers of two and coordinates across the
//! whole `i32` range (the edges, around 2^24 where floats stop holding every integer, and
//! multiples of the size ± 1).

mod common;

use common::Gpu;
use umbra::gpu::kernels::texture_wrap_test;
use umbra::gpu::layout::BufferTestParams;
use umbra::gpu::Pipeline;
use umbra::vk::{raw, Buffer, TexelBuffer};

fn mirror(i: i32, n: i32) -> i32 {
    let period = 2 * n;
    let m = i.rem_euclid(period);
    if m < n {
        m
    } else {
        period - 1 - m
    }
}

#[test]
fn repeat_and_mirror_wrapping_are_exact() {
    let gpu = Gpu::new();
    let sizes =
        [1, 2, 3, 5, 6, 7, 12, 100, 255, 1000, 1023, 1024, 1025, 3000, 4095, 4097, 16383, 65535, 131071];
    let mut cases: Vec<[i32; 2]> = Vec::new();
    let mut state = 0x9e37_79b9u32;
    for &n in &sizes {
        let mut coords = vec![i32::MIN, i32::MIN + 1, i32::MAX, i32::MAX - 1, 0, 1, -1];
        for base in [0i64, 1 << 24, -(1 << 24), 1 << 23, 1 << 30, -(1 << 30)] {
            for k in -3i64..=3 {
                let m = base / n as i64 * n as i64 + k * n as i64;
                coords.extend([m - 1, m, m + 1].map(|v| v.clamp(i32::MIN as i64, i32::MAX as i64) as i32));
            }
        }
        for _ in 0..200 {
            // xorshift: coordinates of every magnitude.
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            coords.push((state as i32) >> (state % 31));
        }
        cases.extend(coords.into_iter().map(|i| [i, n]));
    }
    let count = cases.len() as u32;
    let usage = raw::BufferUsageFlags::STORAGE_BUFFER | raw::BufferUsageFlags::TRANSFER_SRC;
    let input = Buffer::upload(&gpu, "wrap cases", &cases, usage).unwrap();
    let output = Buffer::upload(&gpu, "wrapped", &vec![0i32; 2 * cases.len()], usage).unwrap();
    let textures =
        TexelBuffer::upload(&gpu, "no textures", &[0u32; 8], raw::Format::R32G32B32A32_UINT, 16).unwrap();
    let texels = TexelBuffer::upload(&gpu, "no texels", &[[0u32; 2]], raw::Format::R32G32_UINT, 8).unwrap();
    let pipeline = Pipeline::<texture_wrap_test::Kernel>::plain(&gpu).unwrap();
    gpu.record(|rec| {
        let resources = texture_wrap_test::Resources {
            cases: &input,
            wrapped: &output,
            texture_texels: &textures,
            scene_texels: &texels,
        };
        pipeline.record(rec, &resources, &BufferTestParams { count, add: 0 }, [count, 1, 1])
    })
    .unwrap();
    let out: Vec<i32> = output.read(&gpu).unwrap();
    let mut wrong = 0;
    for (k, &[i, n]) in cases.iter().enumerate() {
        let expected = [i.rem_euclid(n), mirror(i, n)];
        let got = [out[2 * k], out[2 * k + 1]];
        if got != expected {
            if wrong < 10 {
                eprintln!("i = {i}, size = {n}: repeat, mirror {got:?}, expected {expected:?}");
            }
            wrong += 1;
        }
    }
    assert_eq!(wrong, 0, "{wrong} of {} wrapped coordinates differ", cases.len());
}
