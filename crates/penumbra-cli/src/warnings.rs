//! Scene mistakes that are not errors (the scene renders) but almost surely not meant: found by
//! `penumbra check`, printed as warnings on stderr.

use penumbra::{Light, LightModel, World};

/// The warnings of `world` under `model`, each naming the light (`lights[i]`).
pub fn light_warnings(world: &World, model: LightModel) -> Vec<String> {
    let positions = &world.geometry().positions;
    let mut out = Vec::new();
    for (i, light) in world.lights().iter().enumerate() {
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
