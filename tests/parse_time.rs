//! Parsing big robot files grows linearly with the file: `tdcr check` once took 0.38 s for
//! 1 000 tendons and 12.3 s for 8 000, quadratic in the file size. Wall time depends on the
//! machine's load (a timing ratio failed with other builds running on the same two cores),
//! so this test bounds the work instead: the bytes allocated and the number of allocations
//! while parsing and checking, counted by a global allocator enabled only on this test's
//! thread. Both are the same on every run and every machine. They bound the work that
//! allocates (tables, strings, problems, locators); a quadratic loop that allocates nothing
//! would escape them, and the criterion benches (docs/benchmarks.md) measure time.

use std::alloc::{GlobalAlloc, Layout, System as Heap};
use std::cell::Cell;
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;

/// Allocations (and reallocations) and the bytes they asked for, on the counting thread.
static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);
static BYTES: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    static COUNTING: Cell<bool> = const { Cell::new(false) };
}

fn count(size: usize) {
    if COUNTING.with(Cell::get) {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        BYTES.fetch_add(size, Ordering::Relaxed);
    }
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count(layout.size());
        unsafe { Heap.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { Heap.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count(new_size);
        unsafe { Heap.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// A valid robot file with `n` straight tendons, the last one pulled.
fn tendons(n: usize) -> String {
    let mut text =
        String::from("[rod]\nlength = 0.2\nouter_radius = 0.001\nyoungs_modulus = 2e11\npoisson_ratio = 0.3\n");
    for k in 0..n {
        let tension = if k + 1 == n { 1.0 } else { 0.0 };
        text.push_str(&format!(
            "[[tendon]]\nrouting = {{ kind = \"straight\", x = 0.008, y = {:?} }}\ntension = {tension:?}\n",
            1e-9 * k as f64
        ));
    }
    text
}

/// (allocations, bytes) to parse and check `text`, which must be accepted with `n` tendons.
fn work(text: &str, n: usize) -> (f64, f64) {
    ALLOCATIONS.store(0, Ordering::Relaxed);
    BYTES.store(0, Ordering::Relaxed);
    COUNTING.with(|c| c.set(true));
    let file = tdcr::io::parse(text, "big.toml");
    COUNTING.with(|c| c.set(false));
    let counts = (
        ALLOCATIONS.load(Ordering::Relaxed) as f64,
        BYTES.load(Ordering::Relaxed) as f64,
    );
    assert_eq!(file.map(|f| f.robot.tendons.len()).ok(), Some(n));
    counts
}

/// Ten times the tendons take at most 20 times the allocations and the bytes: linear work
/// is 10 times, up to twice that from buffers that grow by doubling (the total allocated by
/// a doubling buffer is between its final size and twice it); quadratic work would be 100.
#[test]
fn parse_work_grows_linearly_with_the_tendons() {
    let (small, large) = (tendons(1000), tendons(10_000));
    let (count_small, bytes_small) = work(&small, 1000);
    let (count_large, bytes_large) = work(&large, 10_000);
    let (count_ratio, bytes_ratio) = (count_large / count_small, bytes_large / bytes_small);
    eprintln!(
        "parse + check: 1 000 tendons {count_small} allocations, {bytes_small} bytes; 10 000 tendons \
         {count_large}, {bytes_large}: ratios {count_ratio:.2}, {bytes_ratio:.2}"
    );
    assert!(
        count_ratio <= 20.0,
        "allocation ratio {count_ratio:.2} for 10 times the tendons"
    );
    assert!(
        bytes_ratio <= 20.0,
        "byte ratio {bytes_ratio:.2} for 10 times the tendons"
    );
}
