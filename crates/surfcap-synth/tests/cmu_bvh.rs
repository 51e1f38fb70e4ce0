//! Every CMU clip in `../shared/data/cmu_bvh`: parsed, checked against its meta.json entry
//! (frames, frame time, joints, end sites, channels, root name and start position), and its
//! root travel read through forward kinematics.

use surfcap_synth::bvh::read_bvh;

#[test]
fn every_cmu_clip_matches_its_metadata() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let dir = data.join("cmu_bvh");
    let meta = surfcap_testkit::meta(&dir);
    let files = meta["files"].as_array().unwrap();
    assert_eq!(files.len(), 8);
    for f in files {
        let name = f["file"].as_str().unwrap();
        let b = read_bvh(&dir.join(name)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(b.n_frames() as u64, f["frames"].as_u64().unwrap(), "{name}: frames");
        assert!((b.frame_time - f["frame_time"].as_f64().unwrap()).abs() < 1e-9, "{name}: frame time");
        let with_channels = b.joints.iter().filter(|j| !j.channels.is_empty()).count();
        assert_eq!(with_channels as u64, f["joints_with_channels"].as_u64().unwrap(), "{name}: joints");
        let end_sites: usize = b.joints.iter().map(|j| j.end_sites.len()).sum();
        assert_eq!(end_sites as u64, f["end_sites"].as_u64().unwrap(), "{name}: end sites");
        assert_eq!(b.n_channels as u64, f["channels"].as_u64().unwrap(), "{name}: channels");
        assert_eq!(b.joints[0].name, f["root_name"].as_str().unwrap(), "{name}: root");
        let root0 = b.world(0)[0].translation.vector;
        let want: Vec<f64> = f["root_start_xyz"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
        for k in 0..3 {
            assert!((root0[k] - want[k]).abs() < 1e-3, "{name}: root start {root0} vs {want:?}");
        }
        // Root horizontal travel (x, z: the files are y-up) against meta.json where given.
        if let Some(d) = f["root_horizontal_displacement"].as_f64() {
            let end = b.world(b.n_frames() - 1)[0].translation.vector;
            let travel = ((end.x - root0.x).powi(2) + (end.z - root0.z).powi(2)).sqrt();
            assert!((travel - d).abs() < 1e-3 * d.max(1.0), "{name}: travel {travel} vs {d}");
        }
    }
}
