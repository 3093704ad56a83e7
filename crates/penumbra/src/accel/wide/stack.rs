//! The stack of the wide tree's walks ([`WideBvh`]'s single-ray queries).

use super::node::{WideNode, WIDTH};
use super::tree::WideBvh;
use crate::accel::STACK_SIZE;

/// Entries of the wide traversal's stack: a wide node pops one entry and pushes at most
/// [`WIDTH`] children, once per level of the binary tree at most (its depth limit keeps it
/// within the binary walks' [`STACK_SIZE`]).
const WIDE_STACK: usize = (WIDTH - 1) * STACK_SIZE + 1;

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

    /// Pushes the children of `node` in `mask` with their entry distances `near`; when
    /// `sorted`, the nearest comes off the stack first.
    #[inline(always)]
    pub(super) fn push_children(
        &mut self,
        tree: &WideBvh,
        node: &WideNode,
        mask: u32,
        near: &[f32; WIDTH],
        sorted: bool,
    ) {
        let start = self.len;
        let mut bits = mask;
        while bits != 0 {
            let lane = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            let (index, count) = node.child(lane);
            tree.prefetch_child(index, count);
            let entry = (index, count, near[lane]);
            let mut k = self.len;
            if sorted {
                // Insertion by decreasing distance among this node's children.
                while k > start && self.entries[k - 1].2 < entry.2 {
                    self.entries[k] = self.entries[k - 1];
                    k -= 1;
                }
            }
            self.entries[k] = entry;
            self.len += 1;
        }
    }
}
