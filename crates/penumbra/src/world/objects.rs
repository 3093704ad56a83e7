//! Triangles named by their object and their index within it, as the AOVs' `primitive_id` and
//! ray casting's geometry and primitive ids name them: an object's triangles are the world's own
//! (each object's contiguous, in object order) or a placed mesh's, in the mesh's order.

use glam::{Vec2, Vec3};

use super::World;
use crate::geometry::{Hit, Surface};
use crate::math::Rgb;

/// Where each object's triangles are.
#[derive(Clone, Debug, Default)]
pub struct ObjectIndex {
    /// By object: its first own triangle and their count (0 for an instance).
    own: Vec<(u32, u32)>,
    /// By object: the instance it is, if it is one.
    instance: Vec<Option<u32>>,
}

/// What a surface point looks like to a sensor, as the renderer shades it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceAttributes {
    /// The diffuse reflectance: the material's k_d times its texture and the vertex colour
    /// (the `albedo` AOV's value for a ray through a pixel's centre).
    pub albedo: Rgb,
    /// Unit interpolated vertex normal of a smooth triangle, else its geometric normal, as
    /// the mesh orients it (not turned toward the ray).
    pub shading_normal: Vec3,
    /// Interpolated texture coordinates.
    pub uv: Vec2,
}

impl ObjectIndex {
    /// The index of `world`'s objects.
    pub fn new(world: &World) -> ObjectIndex {
        let objects = world.objects as usize;
        let mut index = ObjectIndex {
            own: vec![(0, 0); objects],
            instance: vec![None; objects],
        };
        for (i, tri) in world.geometry().triangles.iter().enumerate() {
            let span = &mut index.own[tri.object as usize];
            if span.1 == 0 {
                span.0 = i as u32;
            }
            span.1 += 1;
        }
        for (i, p) in world.placed().iter().enumerate() {
            index.instance[p.object as usize] = Some(i as u32);
        }
        index
    }

    /// The first of `object`'s own triangles (0 for an object with none).
    pub fn first_triangle(&self, object: u32) -> u32 {
        self.own.get(object as usize).map_or(0, |s| s.0)
    }

    /// The hit at parameter `t` and barycentric weights `(b1, b2)` of triangle `primitive` of
    /// `object`; `None` when `world` (the world indexed) has no such triangle.
    pub fn hit(
        &self,
        world: &World,
        object: u32,
        primitive: u32,
        t: f32,
        b: [f32; 2],
    ) -> Option<Hit> {
        let [b1, b2] = b;
        if let Some(&Some(instance)) = self.instance.get(object as usize) {
            let mesh = &world.meshes()[world.placed()[instance as usize].mesh as usize];
            let inside = (primitive as usize) < mesh.len();
            let instance = Some(instance);
            return inside.then_some(Hit {
                t,
                b1,
                b2,
                triangle: primitive,
                instance,
            });
        }
        let &(first, count) = self.own.get(object as usize)?;
        let triangle = first + primitive;
        (primitive < count).then_some(Hit {
            t,
            b1,
            b2,
            triangle,
            instance: None,
        })
    }
}

impl World {
    /// The diffuse reflectance at `surface`: the material's k_d times its texture and the
    /// vertex colour, as shading uses it.
    pub fn albedo(&self, surface: &Surface) -> Rgb {
        let material = &self.materials()[surface.material as usize];
        let tex = match material.texture {
            Some(t) => self.textures()[t as usize].eval(surface.uv),
            None => Vec3::ONE,
        };
        tex * surface.color * material.diffuse
    }

    /// The attributes at barycentric weights `b` of triangle `primitive` of `object`
    /// (`index` is this world's); `None` when there is no such triangle.
    pub fn surface_attributes(
        &self,
        index: &ObjectIndex,
        object: u32,
        primitive: u32,
        b: [f32; 2],
    ) -> Option<SurfaceAttributes> {
        let hit = index.hit(self, object, primitive, 0.0, b)?;
        let surface = self.surface(&hit);
        Some(SurfaceAttributes {
            albedo: self.albedo(&surface),
            shading_normal: surface.shading_normal,
            uv: surface.uv,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::{WorldBuilder, DEFAULT_MATERIAL};

    #[test]
    fn triangles_are_found_by_object_and_index_within_it() {
        let mut b = WorldBuilder::new();
        let tri = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let two = [tri[0], tri[1], tri[2], [1.0, 1.0, 0.0]];
        b.add_triangles(&tri, &[[0, 1, 2]], DEFAULT_MATERIAL)
            .unwrap();
        b.add_triangles(&two, &[[0, 1, 2], [1, 3, 2]], DEFAULT_MATERIAL)
            .unwrap();
        let world = b.build(0);
        let index = ObjectIndex::new(&world);
        let found = |o, p| {
            index
                .hit(&world, o, p, 1.0, [0.25, 0.5])
                .map(|h| h.triangle)
        };
        // Object 1's triangles follow object 0's one.
        assert_eq!(
            (found(0, 0), found(1, 0), found(1, 1)),
            (Some(0), Some(1), Some(2))
        );
        assert_eq!((found(0, 1), found(1, 2), found(2, 0)), (None, None, None));
        assert_eq!(index.first_triangle(1), 1);
        let a = world.surface_attributes(&index, 1, 1, [0.25, 0.5]).unwrap();
        assert_eq!(a.shading_normal, Vec3::Z);
        assert_eq!(a.albedo, world.materials()[0].diffuse);
    }
}
