//! The mutator's edits against hand-worked results, and the runner's contract:
//! `cases` calls, the same inputs from the same seed, a failure that names the
//! seed.

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "test helpers fail the test on any error"
)]

use proptest::prelude::*;
use proptest::sample::Index;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU32, Ordering};
use testkit::{Edit, NUMBERS, Run, Seed, WORDS, apply, fuzz};

const FILE: &[u8] = b"n=12.5e3;\x01\x02\x03\x04";

fn applied(edit: &Edit) -> Vec<u8> {
    let mut bytes = FILE.to_vec();
    apply(&mut bytes, edit);
    bytes
}

proptest! {
    #[test]
    fn set_and_flip_touch_one_byte(i in any::<Index>(), b in any::<u8>(), bit in 0u8..8) {
        let at = i.index(FILE.len());
        let mut want = FILE.to_vec();
        want[at] = b;
        prop_assert_eq!(applied(&Edit::Set(i, b)), want);
        let mut want = FILE.to_vec();
        want[at] ^= 1 << bit;
        prop_assert_eq!(applied(&Edit::Flip(i, 1 << bit)), want);
    }

    #[test]
    fn insert_delete_truncate(i in any::<Index>(), ins in proptest::collection::vec(any::<u8>(), 1..16), len in 1usize..32) {
        let n = FILE.len();
        let at = i.index(n + 1);
        let want = [&FILE[..at], &ins[..], &FILE[at..]].concat();
        prop_assert_eq!(applied(&Edit::Insert(i, ins.clone())), want);

        let at = i.index(n);
        let want = [&FILE[..at], &FILE[(at + len).min(n)..]].concat();
        prop_assert_eq!(applied(&Edit::Delete(i, len)), want);
        prop_assert_eq!(applied(&Edit::Truncate(i)), FILE[..at].to_vec());
    }

    #[test]
    fn number_replaces_the_next_number(i in any::<Index>(), k in 0..NUMBERS.len()) {
        let got = applied(&Edit::Number(i, k));
        let at = i.index(FILE.len());
        // Positions 0..=2 lie before "12.5e3" (bytes 2..8): all of it goes.
        if at <= 2 {
            let want = [&b"n="[..], NUMBERS[k].as_bytes(), &FILE[8..]].concat();
            prop_assert_eq!(got, want);
        } else {
            prop_assert_eq!(&got[..at], &FILE[..at]);
        }
    }

    #[test]
    fn word_overwrites_four_bytes_or_to_the_end(i in any::<Index>(), k in 0..WORDS.len()) {
        let at = i.index(FILE.len());
        let mut want = FILE.to_vec();
        for (j, b) in WORDS[k].to_le_bytes().into_iter().enumerate() {
            if at + j < want.len() {
                want[at + j] = b;
            }
        }
        prop_assert_eq!(applied(&Edit::Word(i, k)), want);
    }

    #[test]
    fn duplicate_copies_a_run(a in any::<Index>(), b in any::<Index>(), len in 1usize..64) {
        let n = FILE.len();
        let from = a.index(n);
        let chunk = &FILE[from..(from + len).min(n)];
        let at = b.index(n + 1);
        let want = [&FILE[..at], chunk, &FILE[at..]].concat();
        prop_assert_eq!(applied(&Edit::Duplicate(a, b, len)), want);
    }

    #[test]
    fn only_insert_grows_an_empty_file(i in any::<Index>(), b in any::<u8>()) {
        for e in [Edit::Set(i, b), Edit::Delete(i, 3), Edit::Number(i, 0), Edit::Word(i, 0)] {
            let mut bytes = Vec::new();
            apply(&mut bytes, &e);
            prop_assert!(bytes.is_empty());
        }
        let mut bytes = Vec::new();
        apply(&mut bytes, &Edit::Insert(i, vec![b, b]));
        prop_assert_eq!(bytes, vec![b, b]);
    }
}

fn seeds() -> Vec<Seed> {
    vec![("a.txt", b"1 2 3\n".to_vec()), ("b.bin", FILE.to_vec())]
}

/// All inputs of a short run, in order.
fn inputs(cases: u32) -> Vec<Seed> {
    let seen = Mutex::new(Vec::new());
    fuzz(Run::Short(cases), seeds(), |name, bytes| {
        let name = if name == "a.txt" { "a.txt" } else { "b.bin" };
        seen.lock().unwrap().push((name, bytes.to_vec()));
        Ok(())
    });
    seen.into_inner().unwrap()
}

#[test]
fn a_short_run_is_cases_calls_and_repeats_itself() {
    let calls = AtomicU32::new(0);
    fuzz(Run::Short(37), seeds(), |_, _| {
        calls.fetch_add(1, Ordering::Relaxed);
        Ok(())
    });
    assert_eq!(calls.into_inner(), 37);

    let first = inputs(200);
    assert_eq!(first.len(), 200);
    assert_eq!(first, inputs(200), "same seed, same inputs");
    // Both seeds are used; some inputs are damaged, some (no edits) are not.
    for (name, bytes) in seeds() {
        assert!(first.iter().any(|(n, _)| *n == name), "{name} unused");
        assert!(first.iter().any(|(n, b)| *n == name && *b == bytes));
        assert!(first.iter().any(|(n, b)| *n == name && *b != bytes));
    }
}

#[test]
#[should_panic(expected = "FUZZ_SEED=")]
fn a_failed_check_names_the_seed() {
    fuzz(Run::Short(64), seeds(), |_, bytes| {
        prop_assert!(!bytes.contains(&b'2'));
        Ok(())
    });
}

#[test]
fn an_error_must_name_its_source() {
    let e = std::io::Error::other("scan.ply: header says 4000000000 vertices");
    assert!(testkit::names_source(&e, "scan.ply").is_ok());
    let msg = testkit::names_source(&e, "rays.bin")
        .unwrap_err()
        .to_string();
    assert!(msg.contains("does not name rays.bin"), "{msg}");
}
