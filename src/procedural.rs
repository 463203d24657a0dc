//! Procedural triangle sets for tests and the benchmark: a closed icosphere (shared vertices are
//! bit-identical, so edges and vertices are exactly shared), a displaced terrain of any size, and
//! random soups and nested clusters; plus a small deterministic random number generator.

use glam::Vec3;
use std::collections::HashMap;

/// SplitMix64: small, fast, deterministic; for generating test inputs, not for rendering.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    /// A generator from a seed.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f32()
    }

    /// Uniform in [0, n).
    pub fn below(&mut self, n: usize) -> usize {
        (((self.next_u64() >> 32) * n as u64) >> 32) as usize
    }

    /// Uniform in the box.
    pub fn in_box(&mut self, lo: Vec3, hi: Vec3) -> Vec3 {
        Vec3::new(self.range(lo.x, hi.x), self.range(lo.y, hi.y), self.range(lo.z, hi.z))
    }

    /// Uniform on the unit sphere.
    pub fn on_sphere(&mut self) -> Vec3 {
        let z = self.range(-1.0, 1.0);
        let phi = self.range(0.0, std::f32::consts::TAU);
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }
}

/// An indexed mesh: vertices and counter-clockwise (outward) triangles.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Triangles as vertex indices.
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    /// The triangles with their vertices.
    pub fn soup(&self) -> Vec<[Vec3; 3]> {
        self.triangles.iter().map(|t| t.map(|i| self.positions[i as usize])).collect()
    }

    /// Unique edges as vertex index pairs (lower index first).
    pub fn edges(&self) -> Vec<[u32; 2]> {
        let mut edges: Vec<[u32; 2]> = self
            .triangles
            .iter()
            .flat_map(|t| [[t[0], t[1]], [t[1], t[2]], [t[2], t[0]]])
            .map(|[a, b]| [a.min(b), a.max(b)])
            .collect();
        edges.sort_unstable();
        edges.dedup();
        edges
    }
}

/// A closed unit icosphere centred at `center` with `radius`: 20·4^subdivisions triangles.
pub fn icosphere(subdivisions: u32, center: Vec3, radius: f32) -> Mesh {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut positions: Vec<Vec3> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|p| Vec3::from(*p).normalize())
    .collect();
    let mut triangles: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, positions: &mut Vec<Vec3>| {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                positions.push((positions[a as usize] + positions[b as usize]).normalize());
                positions.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(triangles.len() * 4);
        for [a, b, c] in triangles {
            let ab = midpoint(a, b, &mut positions);
            let bc = midpoint(b, c, &mut positions);
            let ca = midpoint(c, a, &mut positions);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        triangles = next;
    }
    let positions = positions.into_iter().map(|p| center + p * radius).collect();
    Mesh { positions, triangles }
}

/// A `n × n` quad terrain over `[-size/2, size/2]²` in xz with smooth random hills: 2·n² triangles.
pub fn terrain(n: u32, size: f32, seed: u64) -> Mesh {
    let mut rng = Rng::new(seed);
    let waves: Vec<(f32, f32, f32, f32)> =
        (0..6).map(|_| (rng.range(0.5, 4.0), rng.range(0.5, 4.0), rng.range(0.0, 6.3), rng.f32())).collect();
    let mut positions = Vec::with_capacity(((n + 1) * (n + 1)) as usize);
    for j in 0..=n {
        for i in 0..=n {
            let x = (i as f32 / n as f32 - 0.5) * size;
            let z = (j as f32 / n as f32 - 0.5) * size;
            let y: f32 = waves
                .iter()
                .map(|&(fx, fz, phase, amp)| amp * (fx * x / size * 6.3 + fz * z / size * 6.3 + phase).sin())
                .sum::<f32>()
                * size
                * 0.03;
            positions.push(Vec3::new(x, y, z));
        }
    }
    let mut triangles = Vec::with_capacity((2 * n * n) as usize);
    for j in 0..n {
        for i in 0..n {
            let v = j * (n + 1) + i;
            triangles.push([v, v + n + 1, v + 1]);
            triangles.push([v + 1, v + n + 1, v + n + 2]);
        }
    }
    Mesh { positions, triangles }
}

/// `count` random triangles in the box, each with edges up to `max_edge` long.
pub fn random_soup(count: usize, lo: Vec3, hi: Vec3, max_edge: f32, seed: u64) -> Vec<[Vec3; 3]> {
    let mut rng = Rng::new(seed);
    (0..count)
        .map(|_| {
            let a = rng.in_box(lo, hi);
            [
                a,
                a + rng.on_sphere() * rng.range(0.0, max_edge),
                a + rng.on_sphere() * rng.range(0.0, max_edge),
            ]
        })
        .collect()
}

/// `levels` clusters of `per_level` random small triangles, cluster k at `ratio`^k from the
/// origin along +x and `ratio`^k in size: every coordinate scales with its cluster, so rays near
/// any cluster are as well conditioned as near the first. A SAH BVH over them nests cluster in
/// cluster, a walk deeper than a balanced tree of the same size could be, and a ray from the
/// origin along +x meets every level's cluster and the rest beyond it: it holds one stack entry
/// per level.
pub fn nested_clusters(levels: usize, per_level: usize, ratio: f32, seed: u64) -> Vec<[Vec3; 3]> {
    let mut rng = Rng::new(seed);
    (0..levels)
        .flat_map(|k| std::iter::repeat_n(ratio.powi(k as i32), per_level))
        .map(|s| {
            let a = Vec3::X * s + rng.in_box(Vec3::splat(-0.2 * s), Vec3::splat(0.2 * s));
            [a, a + rng.on_sphere() * (0.03 * s), a + rng.on_sphere() * (0.03 * s)]
        })
        .collect()
}
