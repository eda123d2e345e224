//! Layers become columns folded into bands (a serpentine), and the two small numeric helpers
//! the rows are placed with.

use super::{ASPECT, DY};

/// Layers become columns, folded into bands that run left to right, then right to left (a
/// serpentine: consecutive layers stay neighbours, a cycle closes on itself).
pub(super) struct Bands {
    /// Distance between columns.
    pub(super) dx: f64,
    /// Layers per band.
    pub(super) per_band: usize,
    /// How many bands.
    pub(super) count: usize,
    /// The top row of each band, and below the last one.
    pub(super) top: Vec<f64>,
}

impl Bands {
    /// Folds the layers into bands, moving each band's rows `y` below the one before.
    pub(super) fn fold(layers: &[Vec<usize>], y: &mut [f64], dx: f64) -> Bands {
        let layer_count = layers.len();
        let tallest = layers
            .iter()
            .map(|nodes| span(nodes, y))
            .fold(0.0f64, f64::max)
            + 2.0 * DY;
        let per_band = ((ASPECT * layer_count as f64 * tallest / dx).sqrt().ceil() as usize)
            .max((1080.0 / dx).ceil() as usize)
            .clamp(1, layer_count.max(1));
        // An even number of bands ends on the left, where the first layer is.
        let mut bands = layer_count.div_ceil(per_band).max(1);
        if bands > 2 && bands % 2 == 1 {
            bands -= 1;
        }
        let per_band = layer_count.div_ceil(bands).max(1);
        let bands = layer_count.div_ceil(per_band).max(1);
        let mut top = vec![40.0; bands + 1];
        for b in 0..bands {
            let members =
                &layers[(b * per_band).min(layer_count)..((b + 1) * per_band).min(layer_count)];
            if members.iter().all(Vec::is_empty) {
                top[b + 1] = top[b];
                continue;
            }
            let (lo, hi) = members
                .iter()
                .flatten()
                .fold((f64::MAX, f64::MIN), |(lo, hi), &s| {
                    (lo.min(y[s]), hi.max(y[s]))
                });
            for &s in members.iter().flatten() {
                y[s] += top[b] - lo;
            }
            top[b + 1] = top[b] + (hi - lo) + 2.0 * DY;
        }
        Bands {
            dx,
            per_band,
            count: bands,
            top,
        }
    }

    pub(super) fn band_of(&self, layer: usize) -> usize {
        layer / self.per_band
    }

    /// The column of a layer: bands alternate direction.
    pub(super) fn column(&self, layer: usize) -> usize {
        let (b, c) = (layer / self.per_band, layer % self.per_band);
        if b % 2 == 0 { c } else { self.per_band - 1 - c }
    }
}

/// Values as close as possible (least squares) to `target`, in the same order, each at
/// least `gap` above the one before (pool-adjacent-violators on `target[i] - i·gap`).
pub(super) fn spaced(target: &[f64], gap: f64) -> Vec<f64> {
    // Blocks of (sum, count) of shifted targets, means non-decreasing.
    let mut blocks: Vec<(f64, usize)> = Vec::new();
    for (i, &t) in target.iter().enumerate() {
        blocks.push((t - i as f64 * gap, 1));
        while blocks.len() > 1 {
            let (s2, c2) = blocks[blocks.len() - 1];
            let (s1, c1) = blocks[blocks.len() - 2];
            if s1 / c1 as f64 <= s2 / c2 as f64 {
                break;
            }
            blocks.pop();
            *blocks.last_mut().expect("two blocks") = (s1 + s2, c1 + c2);
        }
    }
    let mut out = Vec::with_capacity(target.len());
    for (s, c) in blocks {
        for _ in 0..c {
            let i = out.len();
            out.push(s / c as f64 + i as f64 * gap);
        }
    }
    out
}

/// Height taken by the slots of one layer.
fn span(nodes: &[usize], y: &[f64]) -> f64 {
    let (lo, hi) = nodes.iter().fold((f64::MAX, f64::MIN), |(lo, hi), &s| {
        (lo.min(y[s]), hi.max(y[s]))
    });
    if nodes.is_empty() { 0.0 } else { hi - lo }
}
