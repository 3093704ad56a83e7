//! The stack of the wide tree's walks (`WideBvh`'s single-ray queries), and the tree size
//! past which a few walks go in turn, each with a stack of its own (`turns`).

use super::node::{WideNode, WIDTH};
use crate::accel::STACK_SIZE;

/// The size of a tree past which its single-ray walks go `INTERLEAVED` (`turns`) rays at a time
/// (`WideBvh::interleaves`). On an AMD EPYC with 2 MiB of L2 per core and a
/// 32 MiB L3, four rays in turn lost to one on the Stanford bunny (4.9 MiB of nodes and
/// triangles) and a 100k-triangle skull (7.5 MiB): the caches serve them, and the turns'
/// bookkeeping has no misses to overlap. A 150k-triangle blob (10.7 MiB) was about even;
/// blobs of 250k, 450k and 1M triangles (18, 32 and 72 MiB) were faster in turns (measured:
/// docs/benchmarks.md, «Design measurements», `INTERLEAVE_BYTES`).
pub(crate) const INTERLEAVE_BYTES: usize = 16 << 20;

/// Entries of a depth-first walk's stack: a wide node pops one entry and pushes at most
/// [`WIDTH`] children, once per level of the binary tree at most (its depth limit keeps it
/// within the binary walks' [`STACK_SIZE`]). From a stack of `n` entries, a depth-first walk
/// holds at most `n + DEPTH_FIRST - 1`.
const DEPTH_FIRST: usize = (WIDTH - 1) * STACK_SIZE + 1;

/// Entries of the wide traversal's stack. An [`Order::Free`] push reorders the stack only
/// when it held at most [`DEPTH_FIRST`] entries before the push, so at most
/// `DEPTH_FIRST + WIDTH` after it; past that the walk goes depth first, adding at most
/// `DEPTH_FIRST - 1` before it reorders again.
const WIDE_STACK: usize = 2 * DEPTH_FIRST + WIDTH;

/// The order in which a walk visits the children of a wide node.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Order {
    /// The nearest child first (closest hits, closest points).
    Nearest,
    /// The last child in lane order first (occlusion: nearest or farthest first were slower;
    /// measured: docs/benchmarks.md, «Design measurements», `Order::Lanes`).
    Lanes,
    /// Any order, every child entered is visited (counting and listing every crossing): the
    /// next visit is the entry pushed before the node's children, whose load started a step
    /// earlier, rather than a child whose load just started. It pays on a tree larger than the
    /// caches (a 1M-triangle blob, 72 MB), where the loads wait on memory, and is even on the
    /// bunny; occlusion in this order was slower (measured: docs/benchmarks.md, «Design
    /// measurements», `Order::Free`).
    Free,
}

/// A stack of the wide traversal, made once per batch and reused from ray to ray: children
/// still to visit as `(index, count, entry distance)`, `count` 0 for the wide node at
/// `index`, else the leaf slots `index .. index + count`.
#[derive(Debug)]
pub(crate) struct Stack {
    entries: Box<[(u32, u32, f32); WIDE_STACK]>,
    len: usize,
}

impl Default for Stack {
    fn default() -> Stack {
        Stack {
            entries: Box::new([(0, 0, 0.0); WIDE_STACK]),
            len: 0,
        }
    }
}

impl Stack {
    /// Starts a traversal of `wide` at its root (nothing for an empty tree).
    #[inline(always)]
    pub(super) fn start(&mut self, wide: &[WideNode]) {
        self.entries[0] = (0, 0, f32::NEG_INFINITY);
        self.len = usize::from(!wide.is_empty());
    }

    #[inline(always)]
    pub(super) fn pop(&mut self) -> Option<(u32, u32, f32)> {
        self.len = self.len.checked_sub(1)?;
        Some(self.entries[self.len])
    }

    /// Pushes the children of `node` in `mask` with their entry distances `near`, to come off
    /// the stack in `order`, asking `prefetch(index, count)` to load each child
    /// (`WideBvh::prefetch_child`).
    #[inline(always)]
    pub(super) fn push_children(
        &mut self,
        prefetch: impl Fn(u32, u32),
        node: &WideNode,
        mask: u32,
        near: &[f32; WIDTH],
        order: Order,
    ) {
        let start = self.len;
        let mut bits = mask;
        while bits != 0 {
            let lane = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            let (index, count) = node.child(lane);
            prefetch(index, count);
            let entry = (index, count, near[lane]);
            let mut k = self.len;
            if order == Order::Nearest {
                // Insertion by decreasing distance among this node's children.
                while k > start && self.entries[k - 1].2 < entry.2 {
                    self.entries[k] = self.entries[k - 1];
                    k -= 1;
                }
            }
            self.entries[k] = entry;
            self.len += 1;
        }
        if order == Order::Free && self.len > start && (1..=DEPTH_FIRST).contains(&start) {
            self.entries.swap(start - 1, self.len - 1);
        }
    }
}
