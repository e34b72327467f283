//! The viewer's clock for moving lights: advances with the frames unless paused (Space)
//! and moves the scene's lights to that time on the GPU (`PreparedFrame::move_lights_to`,
//! after `set_light_motion` on each newly prepared frame).

use crate::reload::ReloadSession;

#[derive(Default)]
pub(crate) struct LightClock {
    /// Seconds of light motion shown.
    pub(crate) time: f64,
    pub(crate) paused: bool,
}

impl LightClock {
    /// Advances by `dt` seconds (unless paused) and moves the live frame's lights there.
    /// A scene without motion costs nothing.
    pub(crate) fn advance(&mut self, session: &ReloadSession, dt: f64) -> Result<(), String> {
        let scene = session.scene();
        if !scene.has_motion() || self.paused {
            return Ok(());
        }
        self.time += dt;
        let Some(prepared) = session.prepared() else {
            return Ok(());
        };
        let r = &session.renderer;
        if !prepared.has_light_motion() {
            prepared
                .set_light_motion(r, session.gpu(), &scene.lights, &scene.light_motion)
                .map_err(|e| e.to_string())?;
        }
        prepared
            .move_lights_to(r, self.time)
            .map_err(|e| e.to_string())
    }
}
