#!/usr/bin/env python3
"""Writes benches/graphs/stochastic_k{K}_{REUSE}.ron from
graphs/visibility_stochastic_shadows.ron: K = 1, 2, 4, 8 reservoirs (shadow rays) a pixel
beyond its 4 exact lights, without reuse (off), with unbiased spatial reuse (spatial), with
biased spatial reuse (biased) and with temporal reuse (history 20) alone (temporal); for
K = 1 and 4 also temporal with the unbiased spatial reuse (spatiotemporal)."""
import pathlib

ROOT = pathlib.Path(__file__).resolve().parent.parent
SHIPPED = "LightSampling(candidates: 8, samples: 1, exact_lights: 4, reuse: Off, seed: 0)"
text = (ROOT / "graphs/visibility_stochastic_shadows.ron").read_text()
assert SHIPPED in text, "the shipped parameters moved"
body = text[text.index("Graph(") :]
SPATIAL = "Unbiased(neighbours: 4, radius: 16)"
BIASED = "Biased(neighbours: 4, radius: 16)"
VARIANTS = [
    ("off", "Off", 0),
    ("spatial", SPATIAL, 0),
    ("biased", BIASED, 0),
    ("temporal", "Off", 20),
    ("spatiotemporal", SPATIAL, 20),
]
for k in [1, 2, 4, 8]:
    for reuse, params, history in VARIANTS:
        if reuse == "spatiotemporal" and k not in (1, 4):
            continue
        name = f"stochastic_k{k}_{reuse}"
        out = body.replace('name: "visibility_stochastic_shadows"', f'name: "{name}"').replace(
            SHIPPED,
            f"LightSampling(candidates: 8, samples: {k}, exact_lights: 4, reuse: {params}, history: {history}, seed: 0)",
        )
        head = (
            "// Written by scripts/stochastic_bench_graphs.py from graphs/visibility_stochastic_shadows.ron:\n"
            f"// {k} reservoirs (shadow rays) a pixel beyond its 4 exact lights, spatial reuse {params}, history {history}.\n"
        )
        (ROOT / f"benches/graphs/{name}.ron").write_text(head + out)
