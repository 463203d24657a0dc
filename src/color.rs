//! Colour conversions, all in one place: the sRGB transfer function both ways, Rec. 709
//! luminance, and the display transforms (exposure, a tone curve, sRGB encoding to 8 bits). The
//! same curves run on the GPU (`spirv/tonemap.comp`, [`crate::passes::tonemap`], for the hybrid
//! pipeline and embedding hosts) and here (for path-traced PNGs and as the reference the kernel is
//! tested against); `texture.glsl` decodes sRGB with a table of [`srgb_decode`].

/// The inverse sRGB transfer function: an encoded value in [0, 1] to linear.
pub fn srgb_decode(encoded: f32) -> f32 {
    if encoded <= 0.040_45 {
        encoded / 12.92
    } else {
        ((encoded + 0.055) / 1.055).powf(2.4)
    }
}

/// The sRGB transfer function of a linear value in [0, 1].
pub fn srgb_encode(linear: f32) -> f32 {
    if linear <= 0.003_130_8 {
        12.92 * linear
    } else {
        1.055 * linear.powf(1.0 / 2.4) - 0.055
    }
}

/// Rec. 709 luminance of linear RGB.
pub fn luminance([r, g, b]: [f32; 3]) -> f32 {
    0.2126 * r + 0.7152 * g + 0.0722 * b
}

/// Linear RGBA (4 floats per pixel) scaled by `exposure`, clamped to [0, 1], sRGB-encoded to
/// 8 bits. NaN becomes 0. Alpha is written linear.
pub fn to_srgb8(rgba: &[f32], exposure: f32) -> Vec<u8> {
    rgba.chunks_exact(4)
        .flat_map(|p| {
            let q = |v: f32, encode: bool| {
                let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
                let v = if encode { srgb_encode(v) } else { v };
                (v * 255.0 + 0.5) as u8
            };
            [q(p[0] * exposure, true), q(p[1] * exposure, true), q(p[2] * exposure, true), q(p[3], false)]
        })
        .collect()
}

/// The tone curve applied after exposure.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum ToneCurve {
    /// Clamp to [0, 1]: exact for values already in range.
    Clamp,
    /// Stephen Hill's fit of the ACES reference rendering transform + sRGB output transform
    /// (the input and output matrices included), as in MJP's BakingLab.
    Aces,
    /// Khronos PBR Neutral (2024): colours below 0.76 pass unchanged (bar a small black-level
    /// offset); highlights compress towards white.
    #[default]
    #[cfg_attr(feature = "cli", value(name = "neutral"))]
    KhronosPbrNeutral,
}

impl ToneCurve {
    /// The code the kernel's push constant uses.
    pub fn code(self) -> u32 {
        match self {
            ToneCurve::Clamp => 0,
            ToneCurve::Aces => 1,
            ToneCurve::KhronosPbrNeutral => 2,
        }
    }
}

fn mul(m: [[f32; 3]; 3], v: [f32; 3]) -> [f32; 3] {
    m.map(|row| row[0] * v[0] + row[1] * v[1] + row[2] * v[2])
}

/// sRGB → ACES AP1 with the RRT's saturation (rows).
const ACES_INPUT: [[f32; 3]; 3] =
    [[0.59719, 0.35458, 0.04823], [0.07600, 0.90834, 0.01566], [0.02840, 0.13383, 0.83777]];
/// ODT's AP1 → sRGB (rows).
const ACES_OUTPUT: [[f32; 3]; 3] =
    [[1.60475, -0.53108, -0.07367], [-0.10208, 1.10813, -0.00605], [-0.00327, -0.07276, 1.07602]];

/// The tone curve of linear `rgb` (already exposed), in [0, 1], NaN to 0.
pub fn tone_curve(rgb: [f32; 3], curve: ToneCurve) -> [f32; 3] {
    let rgb = rgb.map(|c| if c.is_nan() { 0.0 } else { c.max(0.0) });
    let out = match curve {
        ToneCurve::Clamp => rgb,
        ToneCurve::Aces => {
            let fit = |v: f32| {
                (v * (v + 0.024_578_6) - 0.000_090_537) / (v * (0.983_729 * v + 0.432_951) + 0.238_081)
            };
            mul(ACES_OUTPUT, mul(ACES_INPUT, rgb).map(fit))
        }
        ToneCurve::KhronosPbrNeutral => {
            const START: f32 = 0.8 - 0.04;
            const DESATURATION: f32 = 0.15;
            let x = rgb[0].min(rgb[1]).min(rgb[2]);
            let offset = if x < 0.08 { x - 6.25 * x * x } else { 0.04 };
            let c = rgb.map(|v| v - offset);
            let peak = c[0].max(c[1]).max(c[2]);
            if peak < START {
                c
            } else {
                let d = 1.0 - START;
                let new_peak = 1.0 - d * d / (peak + d - START);
                let g = 1.0 - 1.0 / (DESATURATION * (peak - new_peak) + 1.0);
                c.map(|v| v * new_peak / peak * (1.0 - g) + new_peak * g)
            }
        }
    };
    out.map(|v| v.clamp(0.0, 1.0))
}

/// Linear RGBA (4 floats per pixel) × `exposure` through `curve`, sRGB-encoded to 8 bits; alpha
/// written linear.
pub fn to_display8(rgba: &[f32], exposure: f32, curve: ToneCurve) -> Vec<u8> {
    let q = |v: f32| (v * 255.0 + 0.5) as u8;
    rgba.chunks_exact(4)
        .flat_map(|p| {
            let [r, g, b] = tone_curve([p[0] * exposure, p[1] * exposure, p[2] * exposure], curve)
                .map(|v| q(srgb_encode(v)));
            [r, g, b, q(if p[3].is_nan() { 0.0 } else { p[3].clamp(0.0, 1.0) })]
        })
        .collect()
}
