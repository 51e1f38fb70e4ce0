//! A dense warp between texture maps and bilinear resampling through it.
//!
//! A flow `w` maps texel x to x + w(x) (in texels, x to the right, y down the image): warping
//! `I` by `w` gives `I(x + w(x))` (thesis 4.4.1: the forward warp aligns `I` to the reference,
//! `A_ref ~ I(x + w)`; the backward warp de-aligns, `I ~ A(x + w)`).

use crate::error::{Error, Result};
use crate::texture_image::TextureImage;

#[derive(Debug, Clone, PartialEq)]
pub struct FlowField {
    pub width: usize,
    pub height: usize,
    /// Horizontal displacement per texel (row-major).
    pub u: Vec<f32>,
    /// Vertical displacement per texel (row-major).
    pub v: Vec<f32>,
}

impl FlowField {
    /// The identity warp.
    pub fn zeros(width: usize, height: usize) -> FlowField {
        FlowField { width, height, u: vec![0.0; width * height], v: vec![0.0; width * height] }
    }

    /// Checks that the flow is `width x height`.
    pub fn check_size(&self, width: usize, height: usize, what: &str) -> Result<()> {
        if self.width == width
            && self.height == height
            && self.u.len() == width * height
            && self.v.len() == width * height
        {
            return Ok(());
        }
        Err(Error::Mismatch(format!("{what} is {}x{}: expected {width}x{height}", self.width, self.height)))
    }

    /// Mean end-point error against `truth` over the texels where `keep` is true.
    pub fn end_point_error(&self, truth: &FlowField, keep: impl Fn(usize) -> bool) -> f64 {
        let (mut sum, mut n) = (0.0f64, 0usize);
        for i in 0..self.u.len() {
            if keep(i) {
                let du = (self.u[i] - truth.u[i]) as f64;
                let dv = (self.v[i] - truth.v[i]) as f64;
                sum += (du * du + dv * dv).sqrt();
                n += 1;
            }
        }
        if n == 0 { 0.0 } else { sum / n as f64 }
    }
}

/// Bilinear sample of a row-major plane at (x, y) in texel coordinates, clamped to the border.
pub fn sample_bilinear(plane: &[f32], width: usize, height: usize, x: f32, y: f32) -> f32 {
    let x = x.clamp(0.0, (width - 1) as f32);
    let y = y.clamp(0.0, (height - 1) as f32);
    let x0 = x.floor() as usize;
    let y0 = y.floor() as usize;
    let x1 = (x0 + 1).min(width - 1);
    let y1 = (y0 + 1).min(height - 1);
    let fx = x - x0 as f32;
    let fy = y - y0 as f32;
    let top = plane[y0 * width + x0] * (1.0 - fx) + plane[y0 * width + x1] * fx;
    let bottom = plane[y1 * width + x0] * (1.0 - fx) + plane[y1 * width + x1] * fx;
    top * (1.0 - fy) + bottom * fy
}

/// Direct warping (the baseline of thesis Fig. 4.5-4.6): `out(x) = I(x + w(x))`, bilinear.
pub fn warp_direct(image: &TextureImage, flow: &FlowField) -> Result<TextureImage> {
    flow.check_size(image.width(), image.height(), "the flow")?;
    let (w, h) = (image.width(), image.height());
    let mut out = TextureImage::zeros(w, h, image.channels());
    for c in 0..image.channels() {
        let src = image.plane(c);
        let dst = out.plane_mut(c);
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                dst[i] = sample_bilinear(src, w, h, x as f32 + flow.u[i], y as f32 + flow.v[i]);
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_constant_shift_moves_the_image() {
        let data: Vec<f32> = (0..16).map(|i| i as f32).collect();
        let img = TextureImage::from_planes(4, 4, 1, data).unwrap();
        let mut flow = FlowField::zeros(4, 4);
        flow.u.iter_mut().for_each(|u| *u = 1.0);
        let out = warp_direct(&img, &flow).unwrap();
        assert_eq!(out.get(0, 0, 0), 1.0);
        assert_eq!(out.get(0, 2, 1), 7.0);
        assert_eq!(out.get(0, 3, 1), 7.0); // clamped at the border
    }
}
