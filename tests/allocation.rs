//! The Newton loop allocates nothing after setup: a counting global allocator, enabled
//! only on this test's thread, counts every allocation made while Newton runs.

use std::alloc::{GlobalAlloc, Layout, System as Heap};
use std::cell::Cell;
use std::sync::atomic::{AtomicUsize, Ordering};
use tdcr::advanced::equations::Model;
use tdcr::advanced::guess::rigid_estimate;
use tdcr::advanced::mesh::Mesh;
use tdcr::advanced::newton::{self, Settings, Workspace};
use tdcr::advanced::system::System;
use tdcr::collocation::LinearSolver;
use tdcr::{Method, SolveReport, Termination};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    static COUNTING: Cell<bool> = const { Cell::new(false) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if COUNTING.with(Cell::get) {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        unsafe { Heap.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { Heap.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if COUNTING.with(Cell::get) {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        unsafe { Heap.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn newton_loop_does_not_allocate_after_setup() {
    // The counter itself works: one boxed value is one allocation.
    COUNTING.with(|c| c.set(true));
    let boxed = std::hint::black_box(Box::new(1.0f64));
    COUNTING.with(|c| c.set(false));
    drop(boxed);
    assert_eq!(ALLOCATIONS.swap(0, Ordering::Relaxed), 1);
    for solver in [LinearSolver::Blocks, LinearSolver::SparseLu] {
        newton_solve_does_not_allocate(solver);
    }
}

fn newton_solve_does_not_allocate(solver: LinearSolver) {
    for robot in [tdcr::cases::case_s(), tdcr::cases::case_h()] {
        let model = Model::new(&robot);
        let system = System::new(model.clone(), Mesh::uniform(&robot, 64).unwrap());
        let mut ws = Workspace::new(&system, solver).unwrap();
        let settings = Settings {
            tolerance: 1e-11,
            max_iterations: 30,
            reuse_factors: false,
            stop_when_damped: false,
        };
        let mut report = SolveReport::new(Method::Collocation);
        // Setup: buffers sized by a first solve (the trial-state vector gets its capacity).
        let mut x = rigid_estimate(&model, &system.mesh.nodes);
        let warm_up = x.clone();
        assert_eq!(
            newton::run(&system, &mut ws, &mut x, &settings, &mut report).0,
            Termination::Converged
        );
        // Counted: a whole Newton solve from the initial guess again.
        x.clone_from(&warm_up);
        let before = report.iterations;
        COUNTING.with(|c| c.set(true));
        let (termination, _) = newton::run(&system, &mut ws, &mut x, &settings, &mut report);
        COUNTING.with(|c| c.set(false));
        assert_eq!(termination, Termination::Converged);
        assert!(report.iterations > before, "Newton must have iterated");
        assert_eq!(
            ALLOCATIONS.load(Ordering::Relaxed),
            0,
            "allocations inside the Newton loop"
        );
        // Counted: a solve that starts with chord steps on the stored factors.
        x.clone_from(&warm_up);
        let reuse = Settings {
            reuse_factors: true,
            ..settings
        };
        COUNTING.with(|c| c.set(true));
        let (termination, _) = newton::run(&system, &mut ws, &mut x, &reuse, &mut report);
        COUNTING.with(|c| c.set(false));
        assert_eq!(termination, Termination::Converged);
        assert!(
            report.history.iter().any(|it| !it.fresh_jacobian),
            "the stored factors must have been used"
        );
        assert_eq!(
            ALLOCATIONS.load(Ordering::Relaxed),
            0,
            "allocations inside the Newton loop (chord steps)"
        );
    }
}
