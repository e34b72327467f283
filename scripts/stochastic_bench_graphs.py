#!/usr/bin/env python3
"""Writes benches/graphs/stochastic_k{K}_{off,spatial}.ron from
graphs/visibility_stochastic_shadows.ron: K = 1, 2, 4, 8 reservoirs (shadow rays) a pixel
beyond its 4 exact lights, without reuse and with unbiased spatial reuse."""
import pathlib

ROOT = pathlib.Path(__file__).resolve().parent.parent
SHIPPED = "LightSampling(candidates: 8, samples: 1, exact_lights: 4, reuse: Off, seed: 0)"
text = (ROOT / "graphs/visibility_stochastic_shadows.ron").read_text()
assert SHIPPED in text, "the shipped parameters moved"
body = text[text.index("Graph(") :]
for k in [1, 2, 4, 8]:
    for reuse, params in [("off", "Off"), ("spatial", "Unbiased(neighbours: 4, radius: 16)")]:
        name = f"stochastic_k{k}_{reuse}"
        out = body.replace('name: "visibility_stochastic_shadows"', f'name: "{name}"').replace(
            SHIPPED,
            f"LightSampling(candidates: 8, samples: {k}, exact_lights: 4, reuse: {params}, seed: 0)",
        )
        head = (
            "// Written by scripts/stochastic_bench_graphs.py from graphs/visibility_stochastic_shadows.ron:\n"
            f"// {k} reservoirs (shadow rays) a pixel beyond its 4 exact lights, spatial reuse {params}.\n"
        )
        (ROOT / f"benches/graphs/{name}.ron").write_text(head + out)
