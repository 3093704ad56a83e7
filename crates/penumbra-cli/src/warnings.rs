//! Scene mistakes that are not errors (the scene renders) but almost surely not meant: found by
//! `penumbra check`, printed as warnings on stderr: no light at all (which `penumbra render`
//! warns of too), lights that cannot light anything,
//! materials and textures never used, objects no camera sees.

use glam::Vec3;
use penumbra::desc::{InstancesDesc, ShapeDesc, TransformsDesc};
use penumbra::{Aabb, Camera, Light, LightModel, Rgb, SceneDesc, World};

/// The warning for a world with no light at all (no `[[lights]]`, and none from a model
/// file): only the ambient term lights it, and with `ambient` 0 the image is black (but for
/// the background). `None` when there is a light.
pub fn no_light_warning(world: &World, ambient: Rgb) -> Option<String> {
    if !world.lights().is_empty() {
        return None;
    }
    let effect = if ambient == Rgb::ZERO {
        "with render.ambient 0 every surface renders black"
    } else {
        "only render.ambient lights it, evenly and without shadows"
    };
    Some(format!(
        "the scene has no light (no [[lights]] entry, and none from a model file): {effect}"
    ))
}

/// The warnings of `world` under `model`, each naming the light (`lights[i]`).
pub fn light_warnings(world: &World, model: LightModel) -> Vec<String> {
    let positions = &world.geometry().positions;
    let mut out = Vec::new();
    for (i, light) in world.lights().iter().enumerate() {
        if let Light::Environment(e) = light {
            if e.map.mean_and_peak().1 == glam::Vec3::ZERO || e.intensity == 0.0 {
                out.push(format!(
                    "lights[{i}]: the environment is black everywhere: it lights nothing"
                ));
            }
        }
        let Light::Area(a) = light else {
            continue;
        };
        let area = a.area();
        if area <= 0.0 || !area.is_finite() {
            out.push(format!(
                "lights[{i}]: the area light has zero area (u and v are parallel or zero): \
                 under the physical light model it emits nothing, under phong it acts as a point"
            ));
            continue;
        }
        if model != LightModel::Physical {
            continue;
        }
        // Physical area lights emit only toward u × v. Any vertex in front (beyond a small
        // tolerance, so that the light's own quad or a ceiling it lies on does not count)
        // means some geometry can be lit.
        let n = a.normal();
        let tolerance = 1e-4 * (a.u.length() + a.v.length());
        let lights_something = positions.iter().any(|&p| (p - a.center).dot(n) > tolerance);
        if !lights_something {
            out.push(format!(
                "lights[{i}]: the physical area light faces away from all geometry (it emits \
                 toward u × v = [{:.3}, {:.3}, {:.3}]; swap u and v to turn it around)",
                n.x, n.y, n.z
            ));
        }
    }
    out
}

/// `[materials.NAME]` that no object's (or inline placement's) `material` names, and
/// `[textures.NAME]` that no material's `texture` names (a texture named only by an unused
/// material counts as used: that material gets the warning).
pub fn unused_warnings(desc: &SceneDesc) -> Vec<String> {
    let mut out = Vec::new();
    let placements = desc.objects.iter().flat_map(|o| match &o.shape {
        ShapeDesc::Instances(InstancesDesc {
            transforms: TransformsDesc::List(list),
            ..
        }) => list.as_slice(),
        _ => &[],
    });
    let named: Vec<&String> = (desc.objects.iter().filter_map(|o| o.material.as_ref()))
        .chain(placements.filter_map(|p| p.material.as_ref()))
        .collect();
    for (name, _) in &desc.materials.0 {
        if !named.contains(&name) {
            out.push(format!(
                "materials.{name}: the material is never used (no object's `material` names it)"
            ));
        }
    }
    for (name, _) in &desc.textures.0 {
        let used = desc
            .materials
            .0
            .iter()
            .any(|(_, m)| m.texture.as_ref() == Some(name));
        if !used {
            out.push(format!(
                "textures.{name}: the texture is never used (no material's `texture` names it)"
            ));
        }
    }
    out
}

/// Objects that no camera can see: their bounds lie entirely behind the camera or entirely
/// outside one side of its view on a film of aspect `width / height`, for every camera.
/// Conservative: an object reported is surely out of every view (up to a small tolerance); an
/// object outside the view only past a frustum corner is not reported.
pub fn view_warnings(world: &World, aspect: f32, objects: &[(String, Aabb)]) -> Vec<String> {
    let cameras = world.cameras();
    let names: Vec<&str> = cameras.iter().map(|(n, _)| n.as_str()).collect();
    objects
        .iter()
        .filter(|(_, b)| !b.is_empty() && !cameras.is_empty())
        .filter(|(_, b)| cameras.iter().all(|(_, c)| outside_view(c, aspect, b)))
        .map(|(key, _)| {
            format!(
                "{key}: the object is outside the view of every camera ({})",
                names.join(", ")
            )
        })
        .collect()
}

/// Whether `bounds` lies wholly outside one of the planes through `camera`'s eye that bound
/// its view (the plane of the eye facing forward, and the four sides).
fn outside_view(camera: &Camera, aspect: f32, bounds: &Aabb) -> bool {
    let eye = camera.position();
    let forward = (camera.look_at() - eye).normalize_or_zero();
    let right = forward.cross(camera.up()).normalize_or_zero();
    let up = right.cross(forward);
    if forward == Vec3::ZERO || right == Vec3::ZERO || !aspect.is_finite() || aspect <= 0.0 {
        return false;
    }
    // A calibrated K may look off its axis, and other lens models see other views than the
    // centred pinhole's below.
    if !camera.sees_by_fov() {
        return false;
    }
    let half_h = (camera.fov_y_deg().to_radians() / 2.0).tan();
    let half_w = half_h * aspect;
    // Inward normals: a point p is inside a side when (p - eye) · n >= 0.
    let planes = [
        forward,
        forward * half_w - right,
        forward * half_w + right,
        forward * half_h - up,
        forward * half_h + up,
    ];
    let corners: Vec<Vec3> = (0..8)
        .map(|i| {
            Vec3::new(
                if i & 1 == 0 {
                    bounds.min.x
                } else {
                    bounds.max.x
                },
                if i & 2 == 0 {
                    bounds.min.y
                } else {
                    bounds.max.y
                },
                if i & 4 == 0 {
                    bounds.min.z
                } else {
                    bounds.max.z
                },
            )
        })
        .collect();
    // A margin relative to the sizes involved, so that rounding never hides a visible object.
    let scale = corners
        .iter()
        .map(|&c| (c - eye).length())
        .fold(0.0f32, f32::max);
    planes.iter().any(|&n| {
        let n = n.normalize_or_zero();
        corners.iter().all(|&c| (c - eye).dot(n) < -1e-4 * scale)
    })
}
