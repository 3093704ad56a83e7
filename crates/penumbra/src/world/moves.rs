//! Instances that move after the build. A move replaces an instance's transform in place and
//! builds only the top level of the engine again; the mesh trees are untouched. So a world can
//! follow an animation's or a robot's steps without being loaded and built again, and it
//! renders exactly what a world built with the new transforms renders: every query's answer
//! is independent of the shape of the trees.

use super::builder::{check_placement, scale_problem};
use super::{World, WorldError};
use crate::math::Transform;
use crate::scale;

impl World {
    /// Replaces the object-to-world transform of instance `instance` (counted in the order
    /// the instances were added, as [`World::instance_summary`] lists them) with `transform`:
    /// it does not compose with the old one. Refused, with nothing changed, where
    /// [`WorldBuilder::add_instance`](super::WorldBuilder::add_instance) would refuse the
    /// transform, and for an instance that does not exist.
    pub fn set_transform(
        &mut self,
        instance: usize,
        transform: &Transform,
    ) -> Result<(), WorldError> {
        self.set_transforms(&[(instance, *transform)])
    }

    /// [`World::set_transform`] for each of `moves`, in order (a later move of one instance
    /// wins), with the top level built once: all of them, or none when one is refused.
    pub fn set_transforms(&mut self, moves: &[(usize, Transform)]) -> Result<(), WorldError> {
        for (instance, transform) in moves {
            self.check_move(*instance, transform)?;
        }
        for &(instance, transform) in moves {
            self.placed[instance].transform = transform;
        }
        self.accel.set_transforms(moves);
        Ok(())
    }

    /// Whether [`World::set_transform`] takes `transform` for instance `instance`: refused as
    /// [`WorldBuilder::add_instance`](super::WorldBuilder::add_instance) refuses a transform,
    /// or for an instance that does not exist.
    pub fn check_move(&self, instance: usize, transform: &Transform) -> Result<(), WorldError> {
        let Some(p) = self.placed.get(instance) else {
            return Err(WorldError::UnknownInstance {
                index: instance,
                instances: self.placed.len(),
            });
        };
        check_placement(self.mesh_boxes[p.mesh as usize], transform)
    }

    /// The scale check of a world as built, run again on this one (moved instances may take
    /// it past the scales it renders exactly): see `WorldBuilder::scale_problem`.
    pub(crate) fn scale_problem(&self) -> Option<scale::Problem> {
        let meshes = (&self.meshes[..], &self.mesh_boxes[..], &self.placed[..]);
        scale_problem(&self.geometry, meshes, &self.cameras, &self.lights)
    }
}
