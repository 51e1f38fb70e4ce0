//! Smooth extension of the active texels' values over the inactive ones by push-pull
//! (Gortler, Grzeszczuk, Szeliski and Cohen 1996, "The Lumigraph", 3.3): the weighted values
//! are averaged into a half-size image, recursively, until every coarse texel holds a value;
//! then each inactive texel takes the bilinear sample of the filled coarser level. Active
//! texels keep their value.
//!
//! The optical flow needs it ([`crate::tv_l1_flow`]): its Gaussian smoothing, pyramid and
//! bicubic warps read the neighbours of active texels, and a flat background next to a chart
//! would add an artificial edge that pins the flow to zero along every chart border.

use crate::flow_field::sample_bilinear;

/// Fills the texels whose `weight` is zero; `weight` is 1 on active texels, 0 elsewhere.
pub fn push_pull_fill(plane: &[f32], weight: &[f32], width: usize, height: usize) -> Vec<f32> {
    if weight.iter().all(|&w| w > 0.0) || weight.iter().all(|&w| w <= 0.0) {
        return plane.to_vec();
    }
    let (cw, ch) = (width.div_ceil(2), height.div_ceil(2));
    let mut sum = vec![0.0f32; cw * ch];
    let mut wsum = vec![0.0f32; cw * ch];
    for y in 0..height {
        for x in 0..width {
            let i = y * width + x;
            let c = (y / 2) * cw + x / 2;
            sum[c] += weight[i] * plane[i];
            wsum[c] += weight[i];
        }
    }
    let coarse: Vec<f32> = sum.iter().zip(&wsum).map(|(s, w)| if *w > 0.0 { s / w } else { 0.0 }).collect();
    let coarse_weight: Vec<f32> = wsum.iter().map(|&w| if w > 0.0 { 1.0 } else { 0.0 }).collect();
    let filled = push_pull_fill(&coarse, &coarse_weight, cw, ch);
    let mut out = plane.to_vec();
    for y in 0..height {
        for x in 0..width {
            let i = y * width + x;
            if weight[i] <= 0.0 {
                let (fx, fy) = ((x as f32 + 0.5) / 2.0 - 0.5, (y as f32 + 0.5) / 2.0 - 0.5);
                out[i] = sample_bilinear(&filled, cw, ch, fx, fy);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn holes_take_values_between_their_neighbours() {
        let (w, h) = (16, 4);
        let plane: Vec<f32> = (0..w * h)
            .map(|i| {
                if i % w < 4 {
                    10.0
                } else if i % w >= 12 {
                    50.0
                } else {
                    999.0
                }
            })
            .collect();
        let weight: Vec<f32> = plane.iter().map(|&v| if v == 999.0 { 0.0 } else { 1.0 }).collect();
        let out = push_pull_fill(&plane, &weight, w, h);
        for y in 0..h {
            let row = &out[y * w..(y + 1) * w];
            assert!(row[..4].iter().all(|&v| v == 10.0) && row[12..].iter().all(|&v| v == 50.0));
            for x in 4..12 {
                assert!((10.0..=50.0).contains(&row[x]), "{row:?}");
            }
            assert!(row[4] < row[11], "{row:?}");
        }
    }
}
