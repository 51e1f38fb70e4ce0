//! Measures the Poisson texture warp (eq. 4.3) on the real head atlas: the one-off assembly and
//! sparse Cholesky factorisation of `Lᵀ L + λ² I` on the active texels of template.obj's UVs at
//! 1024x1024 (dilation 1), its memory (the factor's entries and the process's peak resident
//! size), and one warp of Map-COL.jpg (3 channels solved together) by a smooth flow.
//!
//! `cargo run --release -p surfcap-appearance --example poisson_warp_timing [data dir] [size]`

use std::path::PathBuf;
use std::time::Instant;

use surfcap_appearance::poisson_texture_warp::{DEFAULT_LAMBDA, PoissonTextureWarp};
use surfcap_appearance::{FlowField, TexelMask, TextureImage};

fn peak_rss_mb() -> f64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find(|l| l.starts_with("VmHWM:"))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|kb| kb.parse::<f64>().ok())
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let data = args.next().map(PathBuf::from).unwrap_or_else(|| PathBuf::from("../shared/data"));
    let size: usize = args.next().map_or(Ok(1024), |s| s.parse())?;
    let head = data.join("leeperrysmith_head");
    let obj = surfcap_formats::obj::read_obj(&head.join("template.obj"))?;
    let topology = obj.topology()?;
    let atlas = topology.uv().ok_or("template.obj has no texture coordinates")?;
    let t = Instant::now();
    let mask = TexelMask::from_atlas(atlas, size, size, 1)?;
    println!(
        "mask {size}x{size}: {} active texels ({:.1}%), {:.2} s",
        mask.len(),
        100.0 * mask.len() as f64 / (size * size) as f64,
        t.elapsed().as_secs_f64()
    );
    let before = peak_rss_mb();
    let t = Instant::now();
    let warp = PoissonTextureWarp::new(&mask, DEFAULT_LAMBDA)?;
    let factor_s = t.elapsed().as_secs_f64();
    println!(
        "factorisation: {factor_s:.2} s, {} factor entries ({:.0} MB as f64 values + row indices), peak RSS {before:.0} -> {:.0} MB",
        warp.factor_entries(),
        warp.factor_entries() as f64 * 16.0 / 1e6,
        peak_rss_mb()
    );
    let mut image = TextureImage::read(&head.join("Map-COL.jpg"))?;
    if image.width() != size {
        // Nearest resample to the mask's size.
        let src = image.clone();
        let mut data = vec![0.0f32; 3 * size * size];
        for c in 0..3 {
            for y in 0..size {
                for x in 0..size {
                    data[c * size * size + y * size + x] = src.get(c, x * src.width() / size, y * src.height() / size);
                }
            }
        }
        image = TextureImage::from_planes(size, size, 3, data)?;
    }
    let mut flow = FlowField::zeros(size, size);
    for y in 0..size {
        for x in 0..size {
            let (fx, fy) = (x as f32 / size as f32, y as f32 / size as f32);
            flow.u[y * size + x] = 3.0 * (std::f32::consts::TAU * fy).sin();
            flow.v[y * size + x] = 2.0 * (std::f32::consts::TAU * fx * 1.5).cos();
        }
    }
    let t = Instant::now();
    let out = warp.warp(&image, &flow)?;
    let solve_s = t.elapsed().as_secs_f64();
    println!(
        "warp of 3 channels: {solve_s:.2} s ({:.2} s per channel incl. right-hand sides), peak RSS {:.0} MB",
        solve_s / 3.0,
        peak_rss_mb()
    );
    let t = Instant::now();
    let _ = surfcap_appearance::flow_field::warp_direct(&image, &flow)?;
    println!("direct warp: {:.3} s", t.elapsed().as_secs_f64());
    std::hint::black_box(out);
    Ok(())
}
