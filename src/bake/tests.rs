use super::*;
use crate::util::test_files::TestDir;

fn temp_dir(tag: &str) -> TestDir {
    TestDir::new(&format!("bake-{tag}"))
}

fn build_counting(calls: &mut u32, value: Vec<f64>) -> impl FnOnce(&mut Progress) -> Result<Vec<f64>> + '_ {
    move |_| {
        *calls += 1;
        Ok(value)
    }
}

#[test]
fn a_second_bake_with_the_same_key_comes_from_the_cache() {
    let dir = temp_dir("hit");
    let key = BakeKey::new("t").with("n", 3);
    let mut calls = 0;
    let a = Baker::new(Some(dir.to_path_buf()))
        .bake("t", &key, build_counting(&mut calls, vec![1.0, 2.5, -3.0]))
        .unwrap();
    let mut baker = Baker::new(Some(dir.to_path_buf()));
    let b = baker.bake("t", &key, build_counting(&mut calls, vec![9.0])).unwrap();
    assert_eq!((a.clone(), b, calls), (vec![1.0, 2.5, -3.0], a, 1));
    assert!(
        baker.reports()[0].cached && baker.reports()[0].bytes == 24,
        "{:?}",
        baker.reports()
    );
}

#[test]
fn a_changed_input_rebuilds() {
    let dir = temp_dir("changed");
    let mut calls = 0;
    let mut baker = Baker::new(Some(dir.to_path_buf()));
    baker
        .bake(
            "t",
            &BakeKey::new("t").with("n", 3),
            build_counting(&mut calls, vec![1.0]),
        )
        .unwrap();
    let v = baker
        .bake(
            "t",
            &BakeKey::new("t").with("n", 4),
            build_counting(&mut calls, vec![2.0]),
        )
        .unwrap();
    let w = baker
        .bake(
            "t",
            &BakeKey::new("t").with("n", 3).with_bytes("mesh", &[1, 2, 3]),
            build_counting(&mut calls, vec![3.0]),
        )
        .unwrap();
    assert_eq!((v, w, calls), (vec![2.0], vec![3.0], 3));
    assert!(baker.reports().iter().all(|r| !r.cached));
}

#[test]
fn corrupt_or_truncated_files_are_rebuilt_not_trusted() {
    let dir = temp_dir("corrupt");
    let key = BakeKey::new("t").with("n", 1);
    let mut calls = 0;
    let mut baker = Baker::new(Some(dir.to_path_buf()));
    baker
        .bake("t", &key, build_counting(&mut calls, vec![1.0, 2.0]))
        .unwrap();
    let path = baker.path("t", &key).unwrap();
    let good = std::fs::read(&path).unwrap();
    // A flipped payload byte, a truncation, garbage, and another key's file under this name.
    let mut flipped = good.clone();
    *flipped.last_mut().unwrap() ^= 0x40;
    let mut other_key = good.clone();
    other_key[8] ^= 1;
    for (bad, why) in [
        (flipped, "checksum"),
        (good[..good.len() - 3].to_vec(), "truncated"),
        (b"hello".to_vec(), "not a penumbra"),
        (other_key, "another key"),
    ] {
        std::fs::write(&path, &bad).unwrap();
        let mut b = Baker::new(Some(dir.to_path_buf()));
        let v = b.bake("t", &key, build_counting(&mut calls, vec![1.0, 2.0])).unwrap();
        assert_eq!(v, vec![1.0, 2.0]);
        let r = &b.reports()[0];
        assert!(
            !r.cached && r.rebuilt.as_deref().is_some_and(|w| w.contains(why)),
            "{why}: {r:?}"
        );
        // The rebuilt file is whole again.
        assert_eq!(std::fs::read(&path).unwrap(), good, "{why}");
    }
    assert_eq!(calls, 5);
}

#[test]
fn without_a_directory_every_bake_runs() {
    let mut calls = 0;
    let mut baker = Baker::new(None);
    let key = BakeKey::new("t");
    baker.bake("t", &key, build_counting(&mut calls, vec![1.0])).unwrap();
    baker.bake("t", &key, build_counting(&mut calls, vec![1.0])).unwrap();
    assert_eq!(calls, 2);
}

#[test]
fn shader_and_byte_inputs_change_the_key() {
    let a = BakeKey::new("t").with_bytes("x", &[1]);
    assert_ne!(a.hash(), BakeKey::new("t").with_bytes("x", &[2]).hash());
    let with = BakeKey::new("t").with_shaders("heightfield/");
    assert_ne!(
        with.hash(),
        BakeKey::new("t").hash(),
        "embedded height-field shaders are part of the key"
    );
    let line = crate::util::progress::line("wedge", 250, 1000, std::time::Duration::from_secs(2));
    assert_eq!(line, "wedge:  25% (250/1000) 125.0/s, 2.0 s elapsed, 6.0 s left");
}

#[test]
fn a_killed_writers_temporaries_are_removed_and_a_live_ones_kept() {
    let dir = temp_dir("stale");
    std::fs::create_dir_all(&dir).unwrap();
    // No process has id 999999999 (Linux's largest is 4194304); process 1 always runs.
    let stale = dir.join("t-0000000000000001.tmp999999999-0");
    let live = dir.join("t-0000000000000002.tmp1-0");
    let other = dir.join("notes.txt");
    for f in [&stale, &live, &other] {
        std::fs::write(f, b"partial").unwrap();
    }
    let mut calls = 0;
    Baker::new(Some(dir.to_path_buf()))
        .bake("t", &BakeKey::new("t"), build_counting(&mut calls, vec![1.0]))
        .unwrap();
    assert!(!stale.exists(), "a temporary of a gone process is left");
    assert!(
        live.exists() && other.exists(),
        "a live writer's temporary or another file was removed"
    );
}

#[test]
fn a_result_that_cannot_be_stored_is_reported_so() {
    let parent = temp_dir("unwritable");
    let dir = parent.join("cache");
    // A file where the cache directory should be: nothing can be stored under it.
    std::fs::write(&dir, b"not a directory").unwrap();
    let mut calls = 0;
    let mut baker = Baker::new(Some(dir.join("bake")));
    baker
        .bake("t", &BakeKey::new("t"), build_counting(&mut calls, vec![1.0]))
        .unwrap();
    let r = &baker.reports()[0];
    assert!(r.not_stored.is_some() && !r.cached, "{r:?}");
    assert!(table(baker.reports()).contains("NOT stored"));
}

#[test]
fn a_cache_only_baker_reads_the_cache_and_refuses_to_build() {
    let dir = temp_dir("cached-only");
    let key = BakeKey::new("t").with("n", 4);
    let mut calls = 0;
    let mut reader = Baker::cached_only(dir.to_path_buf());
    assert!(reader.bake("t", &key, build_counting(&mut calls, vec![1.0])).is_err());
    assert_eq!((reader.missing(), calls), (Some("t"), 0));
    Baker::new(Some(dir.to_path_buf()))
        .bake("t", &key, build_counting(&mut calls, vec![2.0]))
        .unwrap();
    let mut reader = Baker::cached_only(dir.to_path_buf());
    let v = reader.bake("t", &key, build_counting(&mut calls, vec![3.0])).unwrap();
    assert_eq!((v, calls, reader.missing()), (vec![2.0], 1, None));
}

/// A build that stops early because its thread was cancelled returns what it had: the baker
/// reports the bake cancelled and stores nothing; a bake asked for after that does not start.
#[test]
fn a_cancelled_bake_is_not_cached_and_the_next_does_not_start() {
    use crate::util::progress::{cancel_this_thread, Cancel};
    let dir = temp_dir("cancelled");
    let cancel = Cancel::new();
    cancel_this_thread(Some(cancel.clone()));
    let mut baker = Baker::new(Some(dir.to_path_buf()));
    let key = BakeKey::new("t").with("n", 1);
    let stopped = baker.bake("t", &key, |progress| {
        let mut done = Vec::new();
        for i in 0..1000 {
            if i == 10 {
                cancel.cancel();
            }
            if progress.cancelled() {
                break;
            }
            done.push(i as f64);
        }
        Ok(done)
    });
    let mut calls = 0;
    let next = baker.bake("u", &BakeKey::new("u"), build_counting(&mut calls, vec![1.0]));
    cancel_this_thread(None);
    assert!(
        matches!(stopped, Err(Error::Cancelled(ref n)) if n == "t"),
        "{stopped:?}"
    );
    assert!(matches!(next, Err(Error::Cancelled(_))) && calls == 0, "{next:?}");
    let files = std::fs::read_dir(&dir).map(|d| d.count()).unwrap_or(0);
    assert_eq!(files, 0, "nothing written in {}", dir.display());
}
