//! Buffers a thread lends to the stages of its solves: the node lists, node states, rates
//! and scalars per node that a stage fills and a later one is done with (a mesh, a guess, a
//! copy of a residual, the segment ends). A stage takes a buffer here ([`take`]) instead of
//! allocating one and gives it back when done ([`give`]), so that a repeated solve on the
//! same thread allocates only what the [`crate::Solution`] it returns owns (tests/allocation.rs).
//!
//! A buffer not given back is simply dropped (the next take allocates); one taken when none
//! fits grows once. Capacities only grow, so a repeated solve finds every buffer it needs
//! after one solve of the same kind. At most [`SHELF`] buffers of each kind are kept, the
//! largest ones: the memory stays bounded by the largest meshes the thread solved on.

use super::MeshNode;
use crate::solution::{Node, State};
use nalgebra::Vector6;
use std::cell::RefCell;

/// Buffers of one kind a thread keeps: more than a solve holds at once (three of node
/// states: a `Solver`'s last states, Newton's iterate and the equilibrium choice's start or
/// the next mesh's guess; about six of scalars: the model's tensions, the segment ends, the
/// breakpoints, a residual's copy, the estimate's defect and interval errors).
const SHELF: usize = 8;

/// The kept buffers of every kind, each list at most [`SHELF`] long.
#[derive(Default)]
pub(crate) struct Shelves {
    reals: Vec<Vec<f64>>,
    states: Vec<Vec<State>>,
    mesh_nodes: Vec<Vec<MeshNode>>,
    nodes: Vec<Vec<Node>>,
    rates: Vec<Vec<Vector6<f64>>>,
    notes: Vec<String>,
}

thread_local! {
    /// This thread's kept buffers.
    static SHELVES: RefCell<Shelves> = RefCell::new(Shelves::default());
}

/// An element type whose buffers a thread keeps: which list of [`Shelves`] holds them.
pub(crate) trait Kept: Sized {
    /// The list of buffers of this element type.
    fn shelf(shelves: &mut Shelves) -> &mut Vec<Vec<Self>>;
}

impl Kept for f64 {
    fn shelf(shelves: &mut Shelves) -> &mut Vec<Vec<Self>> {
        &mut shelves.reals
    }
}

impl Kept for State {
    fn shelf(shelves: &mut Shelves) -> &mut Vec<Vec<Self>> {
        &mut shelves.states
    }
}

impl Kept for MeshNode {
    fn shelf(shelves: &mut Shelves) -> &mut Vec<Vec<Self>> {
        &mut shelves.mesh_nodes
    }
}

impl Kept for Node {
    fn shelf(shelves: &mut Shelves) -> &mut Vec<Vec<Self>> {
        &mut shelves.nodes
    }
}

impl Kept for Vector6<f64> {
    fn shelf(shelves: &mut Shelves) -> &mut Vec<Vec<Self>> {
        &mut shelves.rates
    }
}

/// An empty buffer with room for at least `len` elements: the smallest kept one that has
/// it, else the largest kept one grown to it, else a new one.
pub(crate) fn take<T: Kept>(len: usize) -> Vec<T> {
    let kept = SHELVES
        .try_with(|shelves| {
            let mut shelves = shelves.borrow_mut();
            let shelf = T::shelf(&mut shelves);
            let fits = (0..shelf.len())
                .filter(|&i| shelf[i].capacity() >= len)
                .min_by_key(|&i| shelf[i].capacity());
            let largest = (0..shelf.len()).max_by_key(|&i| shelf[i].capacity());
            fits.or(largest).map(|i| shelf.swap_remove(i))
        })
        .ok()
        .flatten();
    let mut buffer = kept.unwrap_or_default();
    buffer.clear();
    buffer.reserve_exact(len);
    buffer
}

/// A buffer holding a copy of `values` ([`take`]).
pub(crate) fn copy<T: Kept + Clone>(values: &[T]) -> Vec<T> {
    let mut buffer = take(values.len());
    buffer.extend_from_slice(values);
    buffer
}

/// Keeps `buffer` for a later [`take`] on this thread (its contents are dropped); when
/// [`SHELF`] are kept already, the smallest of them and `buffer` goes.
pub(crate) fn give<T: Kept>(buffer: Vec<T>) {
    if buffer.capacity() == 0 {
        return;
    }
    // A thread being torn down keeps nothing.
    let _ = SHELVES.try_with(|shelves| {
        let mut shelves = shelves.borrow_mut();
        let shelf = T::shelf(&mut shelves);
        if shelf.capacity() == 0 {
            shelf.reserve_exact(SHELF);
        }
        if shelf.len() < SHELF {
            shelf.push(buffer);
        } else if let Some(i) = (0..shelf.len()).min_by_key(|&i| shelf[i].capacity())
            && shelf[i].capacity() < buffer.capacity()
        {
            shelf[i] = buffer;
        }
    });
}

/// A string holding `text`, in a kept buffer ([`give_note`]) when there is one: the
/// "not assessed" reason a report holds until its verdict replaces it.
pub(crate) fn note(text: &str) -> String {
    let kept = SHELVES.try_with(|s| s.borrow_mut().notes.pop()).ok().flatten();
    let mut note = kept.unwrap_or_default();
    note.clear();
    note.push_str(text);
    note
}

/// Keeps the string `note` for a later [`note`] on this thread.
pub(crate) fn give_note(note: String) {
    if note.capacity() == 0 {
        return;
    }
    let _ = SHELVES.try_with(|shelves| {
        let mut shelves = shelves.borrow_mut();
        if shelves.notes.capacity() == 0 {
            shelves.notes.reserve_exact(SHELF);
        }
        if shelves.notes.len() < SHELF {
            shelves.notes.push(note);
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A buffer given back is the one a later take of no more than its capacity gets (the
    /// smallest that fits), with no contents; a take larger than every kept buffer grows
    /// the largest; no more than SHELF are kept.
    #[test]
    fn kept_buffers_are_reused_smallest_fitting_first() {
        std::thread::spawn(|| {
            let (small, large) = (vec![1.0f64; 10], vec![2.0f64; 100]);
            let (small_at, large_at) = (small.as_ptr(), large.as_ptr());
            give(large);
            give(small);
            let a: Vec<f64> = take(5);
            assert!(a.is_empty() && a.as_ptr() == small_at);
            let b: Vec<f64> = take(50);
            assert!(b.is_empty() && b.as_ptr() == large_at);
            give(a);
            let c: Vec<f64> = take(20);
            assert!(c.capacity() >= 20 && c.is_empty());
            for _ in 0..2 * SHELF {
                give(vec![0.0f64; 3]);
            }
            SHELVES.with(|s| assert_eq!(s.borrow().reals.len(), SHELF));
            let text = note("not assessed");
            assert_eq!(text, "not assessed");
            let at = text.as_ptr();
            give_note(text);
            let again = note("not assessed");
            assert!(again == "not assessed" && again.as_ptr() == at);
        })
        .join()
        .unwrap();
    }
}
