//! The Newton loop allocates nothing after setup, and a whole default solve (estimate,
//! verdict, tendon lengths) repeated on a thread allocates only the buffers of the
//! `Solution` it returns: a counting global allocator, enabled only on the counting test's
//! thread, counts every allocation made meanwhile.

use std::alloc::{GlobalAlloc, Layout, System as Heap};
use std::cell::Cell;
use tdcr::advanced::equations::Model;
use tdcr::advanced::guess::rigid_estimate;
use tdcr::advanced::mesh::Mesh;
use tdcr::advanced::newton::{self, Settings, Workspace};
use tdcr::advanced::system::System;
use tdcr::collocation::LinearSolver;
use tdcr::{Method, SolveReport, Termination};

struct Counting;

thread_local! {
    static COUNTING: Cell<bool> = const { Cell::new(false) };
    /// Allocations counted on this thread (each test counts its own, whatever runs beside it).
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

/// The allocations counted on this thread since the last call; resets the count.
fn take_count() -> usize {
    ALLOCATIONS.with(|a| a.replace(0))
}

fn count_one() {
    if COUNTING.with(Cell::get) {
        ALLOCATIONS.with(|a| a.set(a.get() + 1));
    }
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count_one();
        unsafe { Heap.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { Heap.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count_one();
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
    assert_eq!(take_count(), 1);
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
        assert_eq!(take_count(), 0, "allocations inside the Newton loop");
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
        assert_eq!(take_count(), 0, "allocations inside the Newton loop (chord steps)");
    }
}

/// Allocations of one whole solve (`solve`), counted on this thread.
fn allocations_of(solve: impl FnOnce() -> tdcr::Solution) -> (usize, tdcr::Solution) {
    take_count();
    COUNTING.with(|c| c.set(true));
    let solution = solve();
    COUNTING.with(|c| c.set(false));
    (take_count(), solution)
}

/// The buffers `solution` owns, counted twice: as the allocations of a clone (what a
/// solve must at least allocate to return it), and from its fields (the nodes, each
/// tendon's path and tensions and the two lists of them, the tendon states, Newton's
/// history), which must agree. Only for a stable answer without notes (the solves here):
/// other verdicts and notes own strings.
fn solution_buffers(solution: &tdcr::Solution) -> usize {
    assert!(solution.report.stability.is_stable() && solution.report.notes.is_empty());
    let tendons = solution.tendon_paths.len();
    let fields = 1 + (1 + tendons) + (1 + tendons) + 1 + usize::from(!solution.report.history.is_empty());
    let (cloned, _) = allocations_of(|| solution.clone());
    assert_eq!(cloned, fields, "the clone allocates what the fields own");
    cloned
}

/// Two solves before the counted one: the buffers a thread keeps for its solves
/// (workspaces, mesh::spare) reach the number and sizes a solve of this kind needs after
/// one or two (a `Solver` holds one more, the states of its last solve).
const WARM_UP: usize = 2;

#[test]
fn whole_solve_allocations_do_not_grow_with_the_mesh() {
    // The default pipeline (cold guess, equilibrium choice, error estimate, stability
    // verdict, tendon lengths, the Solution) on a fixed mesh of 32 and of 128 intervals,
    // cold and warm (a Solver's stored factors): a repeated or warm solve allocates the
    // Solution's buffers and nothing else, whatever the mesh. Measured (2026-12-06, 32 ->
    // 128 intervals): repeated and warm 15 -> 15, the Solution's own (41 -> 41 and 38 ->
    // 38 before the stages' buffers were kept by the thread and the workspace; 73 -> 83
    // and 65 -> 75 before the cold guess's sweep buffers were kept per thread). A first
    // cold solve on a thread allocates the kept buffers, so it is not mesh-free.
    let counts = |intervals: usize| {
        let options = tdcr::collocation::Options {
            intervals,
            tolerance: None,
            ..Default::default()
        };
        let robot = tdcr::cases::case_h();
        let mut previous = robot.clone();
        for t in previous.tendons.iter_mut() {
            t.set_tension(0.99 * t.tension());
        }
        let (cold, solution) = allocations_of(|| tdcr::collocation::solve(&robot, &options).unwrap());
        assert!(solution.report.error_estimate.is_some() && solution.report.stability.is_stable());
        let owned = solution_buffers(&solution);
        // The same solve again takes the workspace and buffers the first left on this thread.
        let (again, _) = allocations_of(|| tdcr::collocation::solve(&robot, &options).unwrap());
        assert!(
            again < cold,
            "a repeated solve must skip the workspace setup: {again} >= {cold}"
        );
        println!("cold solve on {intervals} intervals: {cold} allocations, repeated {again}");
        let mut solver = tdcr::collocation::Solver::new(options);
        let (warm, solution) = warm_allocations(&mut solver, &previous, &robot);
        assert_eq!(
            solution.report.newton_steps, 0,
            "the warm solve must take chord steps only"
        );
        assert!(solution.report.error_estimate.is_some() && solution.report.stability.is_stable());
        (cold, again, warm, owned)
    };
    let (coarse, fine) = (counts(32), counts(128));
    println!(
        "allocations per solve, 32 -> 128 intervals: cold {} -> {}, repeated {} -> {}, warm {} -> {} \
         (the Solution owns {} -> {})",
        coarse.0, fine.0, coarse.1, fine.1, coarse.2, fine.2, coarse.3, fine.3
    );
    // 24: a Vec built by pushing reallocates about log2(n) times, 2 more for 4 x the
    // intervals; a per-interval allocation would add 96 or more.
    assert!(fine.0 <= coarse.0 + 24, "cold: {coarse:?} -> {fine:?}");
    // Exact: a repeated or warm solve allocates the Solution's buffers, each once at its
    // final size, and nothing else.
    for (repeated, warm, owned) in [(coarse.1, coarse.2, coarse.3), (fine.1, fine.2, fine.3)] {
        assert_eq!(repeated, owned, "repeated: {coarse:?} -> {fine:?}");
        assert_eq!(warm, owned, "warm: {coarse:?} -> {fine:?}");
    }
}

/// The allocations of `solver`'s warm solve of `robot` from its solution of `previous`,
/// after `WARM_UP` such pairs (so that the thread's kept buffers have grown to size).
fn warm_allocations(
    solver: &mut tdcr::collocation::Solver,
    previous: &tdcr::Robot,
    robot: &tdcr::Robot,
) -> (usize, tdcr::Solution) {
    for _ in 0..WARM_UP {
        let guess = solver.solve(previous).unwrap();
        solver.solve_from(robot, &guess).unwrap();
    }
    let guess = solver.solve(previous).unwrap();
    allocations_of(|| solver.solve_from(robot, &guess).unwrap())
}

#[test]
fn default_solves_allocate_only_their_solution() {
    // At default options (error-controlled mesh: H re-meshes from 32 to 85 intervals on
    // a cold solve; estimate, verdict, tendon lengths): a stateless solve repeated on the
    // same thread, a Solver's cold solve after others (a batch row), and a Solver's warm
    // solve from its last solution each allocate exactly the buffers the returned
    // Solution owns (15 for these five-tendon robots; 41 to 64 before 2026-12-06's cuts).
    // The last robot has breakpoints: two tendons end at 0.6 L (two segments, a jump).
    let mut two_sections = tdcr::cases::prototype();
    let length = two_sections.length();
    for i in [0, 2] {
        two_sections.tendons[i].termination = Some(0.6 * length);
    }
    for (name, robot) in [
        ("S", tdcr::cases::case_s()),
        ("H", tdcr::cases::case_h()),
        ("prototype", tdcr::cases::prototype()),
        ("two sections", two_sections),
    ] {
        let options = tdcr::collocation::Options::default();
        for _ in 0..WARM_UP {
            tdcr::collocation::solve(&robot, &options).unwrap();
        }
        let (repeated, solution) = allocations_of(|| tdcr::collocation::solve(&robot, &options).unwrap());
        assert!(solution.report.error_estimate.is_some() && solution.report.tolerance_met == Some(true));
        let owned = solution_buffers(&solution);
        assert_eq!(repeated, owned, "{name}: a repeated stateless solve");
        let mut previous = robot.clone();
        for t in previous.tendons.iter_mut() {
            t.set_tension(0.99 * t.tension());
        }
        let mut solver = tdcr::collocation::Solver::new(options);
        for _ in 0..WARM_UP {
            solver.solve(&previous).unwrap();
        }
        let (cold, solution) = allocations_of(|| solver.solve(&robot).unwrap());
        assert_eq!(cold, solution_buffers(&solution), "{name}: a Solver's cold solve");
        let (warm, solution) = warm_allocations(&mut solver, &previous, &robot);
        assert_eq!(
            solution.report.newton_steps, 0,
            "{name}: the warm solve takes chord steps only"
        );
        assert_eq!(warm, solution_buffers(&solution), "{name}: a Solver's warm solve");
        println!("{name}: repeated {repeated}, Solver cold {cold}, warm {warm}; the Solution owns {owned}");
    }
}

#[test]
fn batch_row_allocations() {
    // What a worker thread of `tdcr batch` runs per row: the default solve (error-controlled
    // mesh, estimate, verdict, tendon lengths) of the prototype by a `Solver` that has solved
    // rows before. It allocates the Solution's buffers and nothing else: 15 (its nodes, each
    // of the 5 tendons' path and tensions and the two lists of them, the tendon states,
    // Newton's history); 39 before 2026-12-06's cuts, 73 before the day's first.
    let mut solver = tdcr::collocation::Solver::new(Default::default());
    let mut robot = tdcr::cases::prototype();
    for (i, tension) in [1.6, 1.0, 2.5, 0.9].into_iter().enumerate() {
        robot.tendons[i].set_tension(tension);
    }
    for _ in 0..WARM_UP {
        solver.solve(&tdcr::cases::prototype()).unwrap();
    }
    let (count, solution) = allocations_of(|| solver.solve(&robot).unwrap());
    assert!(solution.report.error_estimate.is_some() && solution.report.stability.is_stable());
    println!("allocations of a batch row: {count}");
    assert_eq!(
        count,
        solution_buffers(&solution),
        "a batch row allocates beyond its Solution"
    );
}
