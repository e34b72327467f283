// The light_samples buffer a LightSampling pass writes (src/kinds/light_sampling/rules.rs,
// SampleLayout), read by the sampling shader (lighting/light_sampling.wgsl) and by the
// light loop (common/light_loop.wgsl with LIGHT_SAMPLES). The includer declares
// `light_samples: array<u32>` and binds `frame`.
//
// Words: the header (word 0 counts frames; 4..20 the previous frame's view-projection), then SAMPLE_EXACT words a pixel (a light
// traced exactly: its index, bit 31 set when hidden; SAMPLE_NONE unused), then
// SAMPLE_COUNT reservoirs a pixel (light index or SAMPLE_NONE, the contribution weight W
// as f32 bits, the candidates M behind it as f32 bits); with spatial reuse a second
// region of reservoirs follows the first (region 1, what shading then reads); with
// temporal reuse two history regions follow (HISTORY_REGION + frame parity), then two
// regions of surfaces (6 words a pixel: position, geometric normal).
// Defines: SAMPLE_EXACT, SAMPLE_COUNT (u32 constants).

const SAMPLE_HEADER_WORDS: u32 = 20u;
const RESERVOIR_WORDS: u32 = 3u;
const SAMPLE_NONE: u32 = 0xffffffffu;
const SAMPLE_HIDDEN: u32 = 0x80000000u;

fn sample_pixels() -> u32 {
    return frame.size.x * frame.size.y;
}

fn exact_word(pixel: u32, j: u32) -> u32 {
    return SAMPLE_HEADER_WORDS + pixel * SAMPLE_EXACT + j;
}

fn reservoir_word(region: u32, pixel: u32, j: u32) -> u32 {
    let first = SAMPLE_HEADER_WORDS + sample_pixels() * SAMPLE_EXACT;
    return first + (region * sample_pixels() * SAMPLE_COUNT + pixel * SAMPLE_COUNT + j) * RESERVOIR_WORDS;
}
