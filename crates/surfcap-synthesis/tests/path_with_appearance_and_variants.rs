//! Another front end than the command line can make an animation: the built-in mannequin
//! walking and jogging (with its UV atlas), a small variation model trained on it (thesis
//! chapter 6) and an appearance model of one texture per frame (thesis chapter 4), then a
//! path-following animation (thesis 3.5.1) played with a texture per frame and with learned
//! variants on its repeated runs, all through `surfcap_synthesis`'s API.

use surfcap_appearance::appearance_model::{AppearanceOptions, build_appearance_model};
use surfcap_appearance::flow_field::FlowField;
use surfcap_appearance::texel_mask::TexelMask;
use surfcap_appearance::{TextureImage, Warping};
use surfcap_builtin::locomotion::Gait;
use surfcap_builtin::mannequin::{BodyShape, mannequin};
use surfcap_builtin::mannequin_subject::{Clip, mannequin_subject};
use surfcap_mesh::{NoProgress, Subject};
use surfcap_motion::edge_weights::Alpha;
use surfcap_motion::path_following::{Curve, PathSearch};
use surfcap_motion::transition_table::TableParams;
use surfcap_pipeline::{CacheStore, GraphKind, GraphParams, Pipeline};
use surfcap_synthesis::frame_appearance::{FrameTexture, SubjectAppearance};
use surfcap_synthesis::{Output, PathQuery, Prepared, Variation};
use surfcap_variation::VariationModel;
use surfcap_variation::motion_preparation::{PreparationOptions, TimeAlignment};
use surfcap_variation::variation_model::TrainOptions;

/// The mannequin (1,000 vertices, UV-mapped) walking and jogging for 2 s each at 30 fps.
fn walker() -> Subject {
    let mut m = mannequin(&BodyShape::average(), 1000).unwrap();
    let atlas = surfcap_builtin::mannequin_atlas::mannequin_uv_atlas(&m);
    m.topology =
        surfcap_mesh::Topology::new(m.topology.n_vertices(), m.topology.triangles().to_vec(), Some(atlas)).unwrap();
    let clips: Vec<Clip> =
        [Gait::Walk, Gait::Jog].iter().map(|&g| Clip::procedural(&m, g, 30.0, 2.0, 0).unwrap()).collect();
    mannequin_subject("walker", &m, &clips, 30.0).unwrap()
}

/// A variation model of both sequences, a few iterations per part's GPDM.
fn variation_model(s: &Subject) -> VariationModel {
    let (parts, _) = surfcap_transfer::body_parts_proposal::propose(
        s,
        surfcap_transfer::body_parts_proposal::Method::Auto,
        5,
        surfcap_transfer::body_parts_file::DEFAULT_OVERLAP_RINGS,
    )
    .unwrap();
    let mut gpdm = surfcap_learn::gpdm::GpdmOptions::default();
    gpdm.lbfgs.max_iters = 30;
    let options = TrainOptions {
        preparation: PreparationOptions {
            reference: 0,
            time_alignment: TimeAlignment::Uniform,
            blend_pairs: Vec::new(),
            blend_weights: Vec::new(),
        },
        gpdm,
    };
    VariationModel::train(s, &[0, 1], &parts, &options, &NoProgress).unwrap()
}

/// An appearance model of a 16 x 16 map per frame whose colour follows the frame (direct
/// warps with no flow: the maps do not drift).
fn appearance_model(s: &Subject) -> surfcap_appearance::AppearanceModel {
    let (w, h) = (16, 16);
    let mask = TexelMask::from_atlas(s.topology().uv().unwrap(), w, h, 1).unwrap();
    let textures: Vec<TextureImage> = (0..s.n_frames())
        .map(|g| {
            let t = g as f32 / s.n_frames() as f32;
            let data =
                (0..3 * w * h).map(|k| ((k % (w * h)) as f32 / (w * h) as f32 + t * (1 + k / (w * h)) as f32) % 1.0);
            TextureImage::from_planes(w, h, 3, data.collect()).unwrap()
        })
        .collect();
    let names: Vec<String> = (0..s.n_frames()).map(|g| s.frame_index().label(g)).collect();
    let options = AppearanceOptions {
        n_textures: 4,
        n_warps: 2,
        warping: Warping::Direct,
        selection_warping: Warping::Direct,
        ..AppearanceOptions::default()
    };
    let no_flow = |_: &TextureImage, _: &TextureImage| Ok(FlowField::zeros(w, h));
    build_appearance_model(&textures, &names, &mask, &options, &no_flow, &NoProgress).unwrap().0
}

#[test]
fn a_path_played_with_textures_and_variants_without_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let s = walker();
    let model_dir = dir.path().join("walker.variation");
    variation_model(&s).save(&model_dir, false).unwrap();
    let appearance_dir = dir.path().join("walker.appearance");
    appearance_model(&s).save(&appearance_dir, false).unwrap();

    let (l_min, l_max) = surfcap_motion::segment_bounds(s.fps);
    let params = GraphParams {
        table: TableParams { l_min, l_max, slope: Some(3) },
        kind: GraphKind::Essential,
        alpha: Alpha::new(0.05).unwrap(),
    };
    let out = Output::new(dir.path().join("path.glb"));
    let out_path = out.path.clone().unwrap();
    let appearance = SubjectAppearance::open(&appearance_dir, &s, out.format(), &out_path).unwrap();
    let variation = Variation { seed: 3, model: model_dir };
    variation.check(Some(&out_path)).unwrap();
    let pipe = Pipeline::new(s, CacheStore::memory_only(), Box::new(NoProgress));
    let prep =
        Prepared::new(pipe, params, None).unwrap().with_appearance(Some(appearance)).with_variation(Some(variation));

    // A straight line on the ground, long enough that the walk repeats its captured frames.
    let curve = Curve::new(vec![[0.0, 0.0, 0.0], [12.0, 0.0, 0.0]], vec![0, 2]).unwrap();
    let query = PathQuery { curve: &curve, restrictions: &[], start: None, search: PathSearch::for_fps(30.0) };
    let o = prep.follow_path(&query, &out, &NoProgress).unwrap();

    // The path is followed.
    assert!(o.frames > 60, "{} frames", o.frames);
    assert!(o.max_error < 1.0, "largest centre error {} m", o.max_error);
    assert_eq!(o.report.per_frame.error.len(), o.frames);
    assert_eq!(o.constraints.len(), 1);
    // Variants played on the repeats.
    let v = o.report.walk.variation.as_ref().expect("the report's variation");
    assert!(v.repeats > 0 && v.played_as_variants > 0, "{v:?}");
    assert!(v.sequences.iter().all(|q| !q.variants.is_empty()));
    // A texture per frame: reconstructions of captured frames, blends at transitions.
    let a = o.report.walk.appearance.as_ref().expect("the report's appearance");
    assert_eq!(a.per_frame.len(), o.frames);
    assert_eq!(a.textures, a.reconstructed + a.interpolated);
    let blends = a.per_frame.iter().filter(|f| matches!(f, FrameTexture::Blend { .. })).count();
    assert_eq!(blends > 0, o.played.transitions > 0);
    // Written: the textured glb (and its sidecar), and the report beside it, as returned.
    assert!(o.played.written.iter().all(|f| f.exists()));
    let (set, textures) =
        surfcap_formats::glb_frame_set::parse_glb_frame_set_textured(&std::fs::read(&out_path).unwrap(), "path")
            .unwrap();
    assert_eq!(set.frame_count(), o.frames);
    assert_eq!(textures.expect("a texture per frame").images().len(), a.textures);
    let mut written: serde_json::Value =
        serde_json::from_slice(&std::fs::read(o.played.report_path.as_ref().unwrap()).unwrap()).unwrap();
    // Stamped as surfcap's report (so a later run may replace it), then the returned report.
    let stamp = written.as_object_mut().unwrap();
    assert_eq!(stamp.remove("written_by").unwrap(), "surfcap");
    assert_eq!(stamp.remove("output_kind").unwrap(), "report");
    assert_eq!(written, serde_json::to_value(&o.report).unwrap());
    assert_eq!(written["variation"]["seed"], 3);
}
