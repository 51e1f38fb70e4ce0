//! The derived cache as a trust boundary, end to end: entries are never followed through links
//! (a link's target is untouched, the name replaced), the cache folder must be private and
//! outside the inputs, and an entry whose content does not match its hash, or that makes no
//! sense (an all-zero distance matrix, a NaN transfer model), is recomputed with a note.

use std::os::unix::fs::{PermissionsExt, symlink};
use std::path::{Path, PathBuf};

use surfcap_mesh::cache_entry::store_file_entry;
use surfcap_mesh::npy::{read_npy, write_npy};
use surfcap_testkit::{p, stderr, surfcap};

/// The 35-frame walking cat, a small real subject.
fn cat() -> Option<PathBuf> {
    Some(surfcap_testkit::shared_data()?.join("walking_cat_depraz/walk"))
}

/// The cache entries of `dir` whose names start with `prefix` (not their hashes).
fn entries(dir: &Path, prefix: &str) -> Vec<PathBuf> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|f| {
            let n = f.file_name().unwrap().to_string_lossy();
            n.starts_with(prefix) && !n.ends_with(".b3")
        })
        .collect();
    v.sort();
    v
}

/// Runs `distance` on the cat into `cache`, returning the output's stderr.
fn distance(cat: &Path, cache: &Path, out: &Path) -> String {
    let o = surfcap!(&["distance", p(cat), "--fps", "25", "-o", p(out), "--cache-dir", p(cache)]);
    assert!(o.status.success(), "{}", stderr(&o));
    stderr(&o)
}

#[test]
fn a_damaged_distance_entry_linked_to_a_user_file_is_replaced_and_the_file_kept() {
    let Some(cat) = cat() else { return };
    let d = tempfile::tempdir().unwrap();
    let (cache, out) = (d.path().join("cache"), d.path().join("d.npy"));
    distance(&cat, &cache, &out);
    let good = read_npy::<f64>(&out).unwrap();
    let entry = entries(&cache, "distance-").pop().unwrap();
    // The user's file, and a FIFO standing for a device such as /dev/zero.
    let victim = d.path().join("thesis.tex");
    std::fs::write(&victim, b"years of work").unwrap();
    let fifo = d.path().join("pipe");
    assert!(std::process::Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    for target in [&victim, &fifo] {
        std::fs::remove_file(&entry).unwrap();
        symlink(target, &entry).unwrap();
        let e = distance(&cat, &cache, &out);
        assert!(e.contains("symbolic link") && e.contains(&entry.display().to_string()), "{e}");
        assert!(!e.contains("choose another output"), "{e}");
        assert_eq!(std::fs::read(&victim).unwrap(), b"years of work", "the link's target is untouched");
        assert!(std::fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo_like());
        assert!(std::fs::symlink_metadata(&entry).unwrap().is_file(), "the name is an entry again");
        assert_eq!(read_npy::<f64>(&out).unwrap(), good);
    }
}

trait FifoLike {
    fn is_fifo_like(&self) -> bool;
}

impl FifoLike for std::fs::FileType {
    fn is_fifo_like(&self) -> bool {
        std::os::unix::fs::FileTypeExt::is_fifo(self)
    }
}

#[test]
fn all_zero_or_rehashed_distance_entries_are_recomputed_with_a_note() {
    let Some(cat) = cat() else { return };
    let d = tempfile::tempdir().unwrap();
    let (cache, out) = (d.path().join("cache"), d.path().join("d.npy"));
    distance(&cat, &cache, &out);
    let good = read_npy::<f64>(&out).unwrap();
    let entry = entries(&cache, "distance-").pop().unwrap();
    let n = good.shape[0];
    // All zeros with a matching hash: the decoding refuses it.
    store_file_entry(&entry, |w| write_npy(w, &[n, n], &vec![0.0f64; n * n]), &mut |_| {}).unwrap();
    let e = distance(&cat, &cache, &out);
    assert!(e.contains(&entry.display().to_string()) && e.contains("are 0") && e.contains("recomputing"), "{e}");
    assert_eq!(read_npy::<f64>(&out).unwrap(), good);
    assert_eq!(read_npy::<f64>(&entry).unwrap(), good, "the entry was replaced");
    // Decodable and sensible but not what surfcap wrote (its hash no longer matches).
    let mut other = good.data.clone();
    other[1] *= 2.0;
    other[n] *= 2.0;
    let mut bytes = Vec::new();
    write_npy(&mut bytes, &[n, n], &other).unwrap();
    std::fs::write(&entry, bytes).unwrap();
    let e = distance(&cat, &cache, &out);
    assert!(e.contains(&entry.display().to_string()) && e.contains("does not match its hash"), "{e}");
    assert_eq!(read_npy::<f64>(&out).unwrap(), good);
    // Without its hash, too.
    std::fs::remove_file(surfcap_mesh::cache_entry::hash_path(&entry)).unwrap();
    let e = distance(&cat, &cache, &out);
    assert!(e.contains("no content hash"), "{e}");
    assert!(distance(&cat, &cache, &out).is_empty(), "then read quietly");
}

#[test]
fn a_cache_folder_others_can_write_or_inside_an_input_is_refused() {
    let Some(cat) = cat() else { return };
    let d = tempfile::tempdir().unwrap();
    let (cache, out) = (d.path().join("shared"), d.path().join("d.npy"));
    std::fs::create_dir(&cache).unwrap();
    std::fs::set_permissions(&cache, std::fs::Permissions::from_mode(0o777)).unwrap();
    let o = surfcap!(&["distance", p(&cat), "--fps", "25", "-o", p(&out), "--cache-dir", p(&cache)]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(e.contains(&cache.display().to_string()) && e.contains("0777") && e.contains("chmod 700"), "{e}");
    assert_eq!(std::fs::read_dir(&cache).unwrap().count(), 0, "nothing planted");
    // A new cache folder is made private.
    let private = d.path().join("new/cache");
    distance(&cat, &private, &out);
    assert_eq!(std::fs::metadata(&private).unwrap().permissions().mode() & 0o777, 0o700);

    // The input subject is not a cache folder.
    let subject = d.path().join("cat.subject");
    let o = surfcap!(&["--quiet", "import", p(&cat), "--fps", "25", "-o", p(&subject)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let names = |dir: &Path| {
        let mut v: Vec<_> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name()).collect();
        v.sort();
        v
    };
    let before = names(&subject);
    for inside in [subject.clone(), subject.join("cache")] {
        let o = surfcap!(&["distance", p(&subject), "-o", p(&out), "--cache-dir", p(&inside)]);
        assert_eq!(o.status.code(), Some(1));
        let e = stderr(&o);
        assert!(e.contains("the cache folder") && e.contains("the input") && e.contains("--cache-dir"), "{e}");
        assert_eq!(names(&subject), before, "nothing written into the input");
    }
    // A cache folder that holds the input (beside it, not in it) is fine.
    let beside = d.path().join("beside");
    std::fs::create_dir(&beside).unwrap();
    let moved = beside.join("cat.subject");
    std::fs::rename(&subject, &moved).unwrap();
    let o = surfcap!(&["--quiet", "distance", p(&moved), "-o", p(&out), "--cache-dir", p(&beside)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(names(&moved), before, "nothing written into the input");
}

/// Imports one KayKit clip of `character` as a subject cache in `dir`.
fn import(dir: &Path, character: &str) -> Option<PathBuf> {
    let data = surfcap_testkit::shared_data()?;
    let out = dir.join(format!("{character}.subject"));
    let src = data.join(format!("kaykit_adventurers/{character}_Walking_A"));
    let o = surfcap!(&["--quiet", "import", p(&src), "--name", character, "-o", p(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    Some(out)
}

#[test]
fn a_transfer_model_entry_linked_to_a_folder_or_holding_nan_is_trained_again() {
    let d = tempfile::tempdir().unwrap();
    let Some(knight) = import(d.path(), "knight") else { return };
    let Some(barbarian) = import(d.path(), "barbarian") else { return };
    let pairs = d.path().join("pairs.csv");
    std::fs::write(&pairs, "knight_Walking_A:0-32,barbarian_Walking_A:0-32\n").unwrap();
    let cache = d.path().join("cache");
    let train = |out: &str| {
        let out = d.path().join(out);
        let o = surfcap!(&[
            "transfer",
            "train",
            "--whole-body",
            "--source",
            p(&knight),
            "--target",
            p(&barbarian),
            "--pairs",
            p(&pairs),
            "-o",
            p(&out),
            "--cache-dir",
            p(&cache),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        (stderr(&o), out)
    };
    let (_, first) = train("m1");
    let entry = std::fs::read_dir(&cache)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|f| f.is_dir() && f.file_name().unwrap().to_string_lossy().starts_with("transfer-model-"))
        .unwrap();
    // The entry replaced by a link to a folder of the user's: the folder keeps its files.
    let victim = d.path().join("victim");
    std::fs::create_dir(&victim).unwrap();
    std::fs::write(victim.join("keep.txt"), b"mine").unwrap();
    std::fs::remove_dir_all(&entry).unwrap();
    symlink(&victim, &entry).unwrap();
    let (e, _) = train("m2");
    assert!(e.contains("symbolic link") && e.contains("training again"), "{e}");
    let victim_names: Vec<_> = std::fs::read_dir(&victim).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(victim_names, ["keep.txt"]);
    assert_eq!(std::fs::read(victim.join("keep.txt")).unwrap(), b"mine");
    assert!(std::fs::symlink_metadata(&entry).unwrap().is_dir(), "the entry is a folder again");

    // NaN in the cached training poses: the folder no longer matches its hash.
    let npy = entry.join("target_training.npy");
    let mut a = read_npy::<f32>(&npy).unwrap();
    a.data[7] = f32::NAN;
    let nan_model = |path: &Path| {
        let mut bytes = Vec::new();
        write_npy(&mut bytes, &a.shape, &a.data).unwrap();
        std::fs::write(path, bytes).unwrap();
    };
    nan_model(&npy);
    let (e, _) = train("m3");
    assert!(e.contains("do not match their hash") && e.contains("training again"), "{e}");
    let (e, out) = train("m4");
    assert!(!e.contains("training again"), "read back: {e}");
    let model = |dir: &Path| std::fs::read(dir.join("target_training.npy")).unwrap();
    assert_eq!(model(&out), model(&first), "the output holds the trained model, not the NaN one");

    // A saved model holding NaN is refused on load, naming the file.
    nan_model(&out.join("target_training.npy"));
    let motion = format!("{}:knight_Walking_A", p(&knight));
    let o = surfcap!(&["transfer", "apply", p(&out), "--motion", &motion, "-o", p(&d.path().join("x.glb"))]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(e.contains(&out.join("target_training.npy").display().to_string()) && e.contains("finite"), "{e}");
}
