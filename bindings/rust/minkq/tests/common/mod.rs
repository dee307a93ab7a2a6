//! Helpers shared by the integration tests (each test file includes this module).

// Only some test files use these modules, each only some of their helpers: the rest are not
// dead code.
#[allow(dead_code)]
pub mod draped;
#[allow(dead_code)]
pub mod oracle;
#[allow(dead_code)]
pub mod sheets;
#[allow(dead_code)]
pub mod xxh64;

/// splitmix64: the same numbers on every platform.
pub struct Rng(pub u64);
impl Rng {
    pub fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e3779b97f4a7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d049bb133111eb);
        ((z ^ (z >> 31)) >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

/// The two triangles of every cell of an n x n vertex grid (vertex j * n + i).
pub fn grid_triangles(n: i32) -> Vec<[i32; 3]> {
    let mut triangles = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let v00 = j * n + i;
            triangles.push([v00, v00 + 1, v00 + n + 1]);
            triangles.push([v00, v00 + n + 1, v00 + n]);
        }
    }
    triangles
}
