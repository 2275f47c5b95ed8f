//! The GLB reader under arbitrary bytes and under mutations of valid
//! models (bytes flipped, the container cut, numbers of the JSON replaced
//! by any number): it answers a result, never a panic, and never allocates
//! from what a model claims. An allocator that watches the thread reading
//! the model sees its largest single allocation, which must stay within a
//! small multiple of the bytes the model holds (and of the vertex limit
//! given here, which bounds what an accessor without bytes may claim).
//! Bounded in cases, it runs in a few seconds with the other tests.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use glint::bake::{self, Form};
use glint::scene::{Limits, parse_bake};
use proptest::prelude::*;
use serde_json::Value;

use super::bake::hierarchy;
use super::refused::tent;

/// The system allocator, recording the largest allocation of the threads
/// that ask it to.
struct Watch;

thread_local! {
    /// `None` while not watching; else the largest allocation so far.
    static LARGEST: Cell<Option<usize>> = const { Cell::new(None) };
}

// SAFETY: every call is passed to the system allocator unchanged; the
// thread-local it updates is a `Cell` with a const initialiser and no
// destructor, so recording allocates nothing.
unsafe impl GlobalAlloc for Watch {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        record(layout.size());
        // SAFETY: the caller's layout, as given.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: allocated by `System` with this layout.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        record(layout.size());
        // SAFETY: the caller's layout, as given.
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        record(new_size);
        // SAFETY: the caller's pointer, layout and size, as given.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

fn record(size: usize) {
    let _ = LARGEST.try_with(|largest| {
        if let Some(so_far) = largest.get() {
            largest.set(Some(so_far.max(size)));
        }
    });
}

#[global_allocator]
static ALLOCATOR: Watch = Watch;

/// The vertex limit of the fuzzed reads.
const MAX_VERTICES: usize = 1000;

/// Reads and bakes `glb` as the server would (under a small vertex
/// limit), and returns the largest single allocation it made.
fn largest_allocation(glb: &[u8]) -> usize {
    let limits = Limits {
        max_vertices: MAX_VERTICES,
        ..Limits::default()
    };
    LARGEST.with(|l| l.set(Some(0)));
    if let Ok(scene) = parse_bake(None, glb, &limits) {
        let baked = bake::bake(scene, Form::Glb);
        assert!(!baked.body.to_vec(glb).is_empty());
    }
    LARGEST.with(|l| l.replace(None)).expect("watching")
}

/// What reading `glb` may allocate at once: a small multiple of its bytes
/// (its JSON as a tree, its vertices in f64), and of the vertex limit.
fn allowed(glb: &[u8]) -> usize {
    64 * glb.len() + 64 * MAX_VERTICES + 4096
}

fn check(glb: &[u8]) -> Result<(), TestCaseError> {
    let largest = largest_allocation(glb);
    // Reading anything allocates: the watch is live.
    prop_assert!(largest > 0);
    prop_assert!(
        largest <= allowed(glb),
        "allocated {largest} bytes at once for a model of {} bytes",
        glb.len()
    );
    Ok(())
}

/// Valid models to mutate.
fn seeds() -> Vec<Vec<u8>> {
    vec![hierarchy().0.glb(), tent().glb()]
}

/// Every number in `json`, by its pointer.
fn numbers(json: &Value, at: String, out: &mut Vec<String>) {
    match json {
        Value::Number(_) => out.push(at),
        Value::Array(items) => {
            for (i, v) in items.iter().enumerate() {
                numbers(v, format!("{at}/{i}"), out);
            }
        }
        Value::Object(map) => {
            for (k, v) in map {
                numbers(v, format!("{at}/{k}"), out);
            }
        }
        _ => {}
    }
}

fn config() -> ProptestConfig {
    ProptestConfig {
        cases: 256,
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn arbitrary_bytes_are_answered(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
        check(&bytes)?;
        // The same bytes behind a valid header and chunk headers.
        let mut glb = b"glTF".to_vec();
        glb.extend(2u32.to_le_bytes());
        glb.extend(((20 + bytes.len()) as u32).to_le_bytes());
        glb.extend((bytes.len() as u32).to_le_bytes());
        glb.extend(b"JSON");
        glb.extend(&bytes);
        check(&glb)?;
    }

    #[test]
    fn valid_models_with_bytes_changed_are_answered(
        seed in 0..2usize,
        changes in proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..8),
        cut in any::<prop::sample::Index>(),
        truncate in any::<bool>(),
    ) {
        let mut glb = seeds().swap_remove(seed);
        for (at, byte) in changes {
            let i = at.index(glb.len());
            glb[i] = byte;
        }
        if truncate {
            glb.truncate(cut.index(glb.len()));
        }
        check(&glb)?;
    }

    #[test]
    fn valid_models_with_numbers_changed_are_answered(
        seed in 0..2usize,
        changes in proptest::collection::vec(
            (any::<prop::sample::Index>(), prop_oneof![
                any::<u64>(),
                0..64u64,
                Just(u64::from(u32::MAX)),
                Just(1u64 << 32),
                Just(u64::MAX),
            ]),
            1..4,
        ),
    ) {
        let seed = seeds().swap_remove(seed);
        let json_length = u32::from_le_bytes(seed[12..16].try_into().unwrap()) as usize;
        let mut json: Value = serde_json::from_slice(&seed[20..20 + json_length]).unwrap();
        let bin = if 20 + json_length < seed.len() { seed[28 + json_length..].to_vec() } else { Vec::new() };
        let mut pointers = Vec::new();
        numbers(&json, String::new(), &mut pointers);
        for (at, value) in changes {
            let pointer = &pointers[at.index(pointers.len())];
            *json.pointer_mut(pointer).unwrap() = Value::from(value);
        }
        let glb = super::support::glb(&serde_json::to_vec(&json).unwrap(), &bin);
        check(&glb)?;
    }
}
