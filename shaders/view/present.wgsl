// The viewer's last step: the graph's HDR output, scaled to the window, through the same
// exposure and Reinhard curve as bench::Tonemap (PNG output and FLIP). The window's
// sRGB format applies the transfer function; SRGB_ENCODE does it here when it cannot.
#include "common/fullscreen_vs.wgsl"

struct PresentParams {
    exposure_scale: f32,
    _pad: f32,
    target_size: vec2<f32>,
}

@group(0) @binding(0) var hdr: texture_2d<f32>;
@group(0) @binding(1) var<uniform> params: PresentParams;

fn tone(x: f32) -> f32 {
    // NaN shows black and +inf white, as on the CPU side.
    if (x != x) {
        return 0.0;
    }
    if (x > 3.0e38) {
        return 1.0;
    }
    let e = max(x * params.exposure_scale, 0.0);
    return e / (1.0 + e);
}

fn srgb(x: f32) -> f32 {
    if (x <= 0.0031308) {
        return 12.92 * x;
    }
    return 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}

@fragment
fn present_fs(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    let size = vec2<f32>(textureDimensions(hdr));
    let texel = vec2<i32>(min(floor(pos.xy * size / params.target_size), size - 1.0));
    let c = textureLoad(hdr, texel, 0);
    var rgb = vec3<f32>(tone(c.r), tone(c.g), tone(c.b));
    if (SRGB_ENCODE) {
        rgb = vec3<f32>(srgb(rgb.r), srgb(rgb.g), srgb(rgb.b));
    }
    return vec4<f32>(rgb, 1.0);
}
