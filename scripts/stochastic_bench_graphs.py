#!/usr/bin/env python3
"""Writes benches/graphs/stochastic_k{K}_{REUSE}.ron from
graphs/visibility_stochastic_shadows.ron: K = 1, 2, 4, 8 reservoirs (shadow rays) a pixel
beyond its 4 exact lights, without reuse (off), with unbiased spatial reuse (spatial), with
biased spatial reuse (biased) and with temporal reuse (history 20) alone (temporal); for
K = 1 and 4 also temporal with the unbiased spatial reuse (spatiotemporal). And
benches/graphs/stochastic_n0_k{K}_m8_temporal.ron: no exact lights (the sampling pass
never walks the whole tile list), K = 1, 2, 4 reservoirs of 8 candidates, temporal reuse.
And benches/graphs/stochastic_block4_k{K}_m8_{REUSE}.ron: 4 exact lights chosen once for
each 8x8 block (exact_per: Block)."""
import pathlib

ROOT = pathlib.Path(__file__).resolve().parent.parent
SHIPPED = "LightSampling(candidates: 8, samples: 1, exact_lights: 4, reuse: Off, seed: 0)"
text = (ROOT / "graphs/visibility_stochastic_shadows.ron").read_text()
assert SHIPPED in text, "the shipped parameters moved"
body = text[text.index("Graph(") :]
DESCRIBED = "the 4 strongest casting lights a pixel traced exactly, one resampled light for the rest"
assert DESCRIBED in body, "the shipped description moved"
SPATIAL = "Unbiased(neighbours: 4, radius: 16)"
BIASED = "Biased(neighbours: 4, radius: 16)"
VARIANTS = [
    ("off", "Off", 0),
    ("spatial", SPATIAL, 0),
    ("biased", BIASED, 0),
    ("temporal", "Off", 20),
    ("spatiotemporal", SPATIAL, 20),
]


def write(name, k, m, exact, params, history, per=""):
    words = {1: "one", 2: "two", 4: "four", 8: "eight"}
    said = f"the {exact} strongest casting lights a pixel traced exactly, " if exact else "no light traced exactly, "
    if per:
        said = f"the {exact} strongest casting lights of each 8x8 block traced exactly, "
    said += f"{words[k]} resampled light{'s' if k > 1 else ''} of {m} candidates for the rest"
    out = body.replace(DESCRIBED, said).replace('name: "visibility_stochastic_shadows"', f'name: "{name}"').replace(
        SHIPPED,
        f"LightSampling(candidates: {m}, samples: {k}, exact_lights: {exact}, {per}reuse: {params}, history: {history}, seed: 0)",
    )
    head = (
        "// Written by scripts/stochastic_bench_graphs.py from graphs/visibility_stochastic_shadows.ron:\n"
        f"// {k} reservoirs (shadow rays) of {m} candidates a pixel beyond its {exact} exact lights{' (chosen a block)' if per else ''}, spatial reuse {params}, history {history}.\n"
    )
    (ROOT / f"benches/graphs/{name}.ron").write_text(head + out)


for k in [1, 2, 4, 8]:
    for reuse, params, history in VARIANTS:
        if reuse == "spatiotemporal" and k not in (1, 4):
            continue
        write(f"stochastic_k{k}_{reuse}", k, 8, 4, params, history)
for k in [1, 2, 4]:
    write(f"stochastic_n0_k{k}_m8_temporal", k, 8, 0, "Off", 20)
for exact, k, reuse, history in [(4, 1, "off", 0), (4, 1, "temporal", 20), (4, 2, "temporal", 20)]:
    write(f"stochastic_block{exact}_k{k}_m8_{reuse}", k, 8, exact, "Off", history, "exact_per: Block, ")
