//! `surfcap-bench graph`: essential and motion graph build times on a seeded random table.

use std::time::Instant;

use serde_json::json;

use crate::options::{AlphaOpt, SeedOpt};

#[derive(clap::Args, Debug)]
pub struct Args {
    #[arg(long, default_value_t = 2000, value_parser = crate::options::count)]
    pub frames: usize,
    /// Sequences the frames are split into.
    #[arg(long, default_value_t = 20, value_parser = crate::options::count)]
    pub sequences: usize,
    #[command(flatten)]
    pub alpha: AlphaOpt,
    #[command(flatten)]
    pub seed: SeedOpt,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let (frames, sequences, alpha, seed) = (a.frames, a.sequences, a.alpha.value(), a.seed.seed);
    // The random table's costs and durations and the edge weights: a few f64 matrices.
    let f = frames as f64;
    crate::check_size(ctx, format!("--frames {frames}"), f * f * 8.0 * 4.0, 0.0, "--frames")?;
    use surfcap_motion::edge_weights::edge_weights;
    use surfcap_motion::essential_graph::essential_graph;
    use surfcap_motion::motion_graph::motion_graph;
    use surfcap_motion::transition_table::TransitionTable;
    anyhow::ensure!(
        sequences >= 1 && frames >= 2 * sequences,
        "--frames {frames} --sequences {sequences}: expected at least two frames per sequence"
    );
    let index =
        surfcap_mesh::FrameIndex::new((0..sequences).map(|k| frames / sequences + usize::from(k < frames % sequences)));
    let n = frames;
    // A seeded, platform-independent stream for the table's values (as surfcap-eval's Mantel test).
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let cost: Vec<f64> = (0..n * n).map(|_| rng.random_range(0.5..1.5)).collect();
    let len: Vec<u32> = (0..n * n).map(|_| rng.random_range(10..60)).collect();
    let table = TransitionTable { n, cost, len, li: vec![10; n * n], lj: vec![10; n * n] };
    let t0 = Instant::now();
    let w = edge_weights(&table, &index, alpha)?;
    let t_weights = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let eg = essential_graph(&w, &crate::progress::Bar::new(ctx));
    let t_essential = t1.elapsed().as_secs_f64();
    let t2 = Instant::now();
    let mg = motion_graph(&w, &index);
    let t_motion = t2.elapsed().as_secs_f64();
    let report = json!({
        "frames": n, "sequences": sequences, "alpha": alpha, "threads": rayon::current_num_threads(),
        "edge_weights_seconds": t_weights, "essential_graph_seconds": t_essential, "motion_graph_seconds": t_motion,
        "essential_edges": eg.graph.edges().len(), "essential_density": eg.graph.density(),
        "motion_edges": mg.graph.edges().len(), "motion_density": mg.graph.density(),
    });
    ctx.result(&report, || {
        println!(
            "{n} nodes ({sequences} sequences), {} threads: edge weights {t_weights:.2} s, essential graph {t_essential:.2} s ({} edges, density {:.4}), motion graph {t_motion:.2} s ({} edges)",
            rayon::current_num_threads(),
            eg.graph.edges().len(),
            eg.graph.density(),
            mg.graph.edges().len()
        );
    });
    Ok(())
}
