//! The training pairs of a transfer from the user's key pairs (thesis 5.5.1 then 5.5.2: "using
//! the densification approach ... we can augment the set of source and target pose
//! correspondences using all the motion sequences present in the training datasets").
//!
//! Key pairs are grouped by the (source sequence, target sequence) they join; each group of at
//! least two keys is densified over the two whole sequences
//! ([`crate::correspondence_densification`], with per-part PCA coefficients of every frame of
//! both subjects' training sequences), and the dense pairs replace the keys. A group with a
//! single key pair cannot fit the linear association model of eq. 5.4-5.8, so its key is kept
//! as it is (and reported).

use faer::Mat;
use serde::{Deserialize, Serialize};

use crate::body_parts::BodyParts;
use crate::correspondence_densification::{DensifyOptions, densify};
use crate::error::{Error, Result};
use crate::motion_transfer::{PreparedSubject, match_parts};
use crate::pose_representation::PartSpace;

/// A pair of frames (source, target): global frames, or frames of one sequence each.
pub type FramePair = (usize, usize);

/// What happened to one group of key pairs.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct GroupReport {
    /// `sequence` names are filled in by the caller that knows them; here the indices.
    pub source_sequence: usize,
    pub target_sequence: usize,
    pub keys: usize,
    /// Pairs after densification (the keys themselves when not densified).
    pub pairs: usize,
    pub densified: bool,
    /// Mean association cost per node of the dense path (eq. 5.10 over the path length).
    pub mean_cost: Option<f64>,
}

/// Dense training pairs (global frames) from key pairs (global frames).
pub fn densified_pairs(
    source: &PreparedSubject,
    source_parts: &BodyParts,
    target: &PreparedSubject,
    target_parts: &BodyParts,
    keys: &[FramePair],
    components: usize,
    opts: &DensifyOptions,
) -> Result<(Vec<FramePair>, Vec<GroupReport>)> {
    let source_of = match_parts(source_parts, target_parts)?;
    let src_space = PartSpace::fit(source_parts, &source.all_poses(), components)?;
    let tgt_space = PartSpace::fit(target_parts, &target.all_poses(), components)?;
    let locate = |p: &PreparedSubject, g: usize, who: &str| {
        p.locate(g).ok_or_else(|| Error::Invalid(format!("{who} frame {g} is not a frame of the subject")))
    };
    // Groups in order of first appearance.
    let mut groups: Vec<(FramePair, Vec<FramePair>)> = Vec::new();
    for &(gs, gt) in keys {
        let (ss, fs) = locate(source, gs, "source")?;
        let (st, ft) = locate(target, gt, "target")?;
        match groups.iter_mut().find(|g| g.0 == (ss, st)) {
            Some(g) => g.1.push((fs, ft)),
            None => groups.push(((ss, st), vec![(fs, ft)])),
        }
    }
    let coefficients = |p: &PreparedSubject, space: &PartSpace, k: usize, seq: usize| -> Result<Mat<f64>> {
        let poses: Vec<&[f32]> = p.range(seq).map(|g| p.frame(g).map(|f| f.0)).collect::<Result<_>>()?;
        space.encode(k, &poses)
    };
    let mut pairs = Vec::new();
    let mut reports = Vec::new();
    for ((ss, st), local) in groups {
        let (rs, rt) = (source.range(ss), target.range(st));
        if local.len() < 2 {
            pairs.extend(local.iter().map(|&(a, b)| (rs.start + a, rt.start + b)));
            reports.push(GroupReport {
                source_sequence: ss,
                target_sequence: st,
                keys: local.len(),
                pairs: local.len(),
                densified: false,
                mean_cost: None,
            });
            continue;
        }
        let mut sp = Vec::new();
        let mut tp = Vec::new();
        for (k, &sk) in source_of.iter().enumerate() {
            sp.push(coefficients(source, &src_space, sk, ss)?);
            tp.push(coefficients(target, &tgt_space, k, st)?);
        }
        let d = densify(&sp, &tp, &local, opts)?;
        reports.push(GroupReport {
            source_sequence: ss,
            target_sequence: st,
            keys: local.len(),
            pairs: d.pairs.len(),
            densified: true,
            mean_cost: Some(d.cost / d.pairs.len().max(1) as f64),
        });
        pairs.extend(d.pairs.iter().map(|&(a, b)| (rs.start + a, rt.start + b)));
    }
    Ok((pairs, reports))
}
