//! The viewer's clock for moving lights: advances with the frames unless paused (Space)
//! and writes the scene's lights at that time through `PreparedFrame::update_lights`.

use crate::reload::ReloadSession;
use crate::scene::Light;

#[derive(Default)]
pub(crate) struct LightClock {
    /// Seconds of light motion shown.
    pub(crate) time: f64,
    pub(crate) paused: bool,
    /// The lights at `time`, kept so that a frame allocates nothing.
    lights: Vec<Light>,
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
        scene.lights_at(self.time, &mut self.lights);
        prepared
            .update_lights(&session.renderer, session.gpu(), &self.lights)
            .map_err(|e| e.to_string())
    }
}
