//! The test scenes: sheets that come close to themselves in many places, a flat grid, and
//! positions far from those a scene's trees were built for.

use super::oracle::Mesh;
use super::{grid_triangles, Rng};

/// An n x n sheet rolled up about 1.4 turns (layers ~0.035 apart), jittered; `phase` shifts
/// the roll so that successive steps move every vertex.
pub fn rolled_sheet(n: i32, seed: u64, phase: f64) -> Vec<[f32; 3]> {
    let mut rng = Rng(seed);
    let mut vertices = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let (u, v) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
            let angle = 9.0 * u + phase;
            let radius = 0.2 + 0.05 * u;
            vertices.push([
                (radius * angle.cos() + 0.02 * (rng.uniform() - 0.5)) as f32,
                (v + 0.02 * (rng.uniform() - 0.5)) as f32,
                (radius * angle.sin() + 0.02 * (rng.uniform() - 0.5)) as f32,
            ]);
        }
    }
    vertices
}

/// A crumpled n x n sheet folded over itself, so that it comes close to itself in many places:
/// `rolled_sheet` at phase 0, triangulated by `grid_triangles`.
pub fn crumpled_sheet(n: i32, seed: u64) -> Mesh {
    Mesh { vertices: rolled_sheet(n, seed, 0.0), triangles: grid_triangles(n) }
}

/// A flat n x n grid over the unit square (z = 0), triangulated by `grid_triangles`.
pub fn flat_grid(n: i32) -> Mesh {
    let step = 1.0 / (n - 1) as f32;
    let vertices = (0..n * n).map(|k| [(k % n) as f32 * step, (k / n) as f32 * step, 0.0]).collect();
    Mesh { vertices, triangles: grid_triangles(n) }
}

/// The flat grid's vertices (x = u, y = v) rolled up about the y axis as `rolled_sheet`
/// rolls its sheet (~1.4 turns, the layers ~0.035 apart), each row then turned about the y
/// axis by `twist` v radians: far from the positions the trees were built for.
pub fn rolled_and_twisted(flat: &[[f32; 3]], twist: f64) -> Vec<[f32; 3]> {
    flat.iter()
        .map(|p| {
            let (u, v) = (p[0] as f64, p[1] as f64);
            let (angle, radius) = (9.0 * u, 0.2 + 0.05 * u);
            let (x, z) = (radius * angle.cos(), radius * angle.sin());
            let (c, s) = ((twist * v).cos(), (twist * v).sin());
            [(c * x - s * z) as f32, v as f32, (s * x + c * z) as f32]
        })
        .collect()
}

pub fn scaled(vertices: &[[f32; 3]], factor: f32) -> Vec<[f32; 3]> {
    vertices.iter().map(|p| [p[0] * factor, p[1] * factor, p[2] * factor]).collect()
}
