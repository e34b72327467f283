#!/usr/bin/env python3
"""Writes benches/scenes/one_material/: copies of the JSON of Khronos glTF models with many
materials in which every primitive uses the model's first material, their buffers read
from the originals under tests/assets/khronos/. The material-count benchmark shades a
model and its one-material copy (the same triangles, pixels and material code) to show
what the number of materials costs visibility shading. Run from the repository root;
the output is committed, so run it again only when the models change."""

import json
import os
import shutil

MODELS = ["MetalRoughSpheresNoTextures", "2CylinderEngine"]
SOURCE = "tests/assets/khronos"
OUT = "benches/scenes/one_material"


def main():
    os.makedirs(OUT, exist_ok=True)
    for model in MODELS:
        folder = os.path.join(SOURCE, model)
        with open(os.path.join(folder, model + ".gltf")) as f:
            doc = json.load(f)
        for mesh in doc["meshes"]:
            for primitive in mesh["primitives"]:
                primitive["material"] = 0
        doc["materials"] = doc["materials"][:1]
        # Buffers and images stay where they are: their URIs are made relative to OUT.
        for entry in doc.get("buffers", []) + doc.get("images", []):
            if "uri" in entry and not entry["uri"].startswith("data:"):
                entry["uri"] = os.path.relpath(os.path.join(folder, entry["uri"]), OUT)
        with open(os.path.join(OUT, model + "_one_material.gltf"), "w") as f:
            json.dump(doc, f, separators=(",", ":"))
        # The model's README (its licence) goes with every copy.
        shutil.copy(os.path.join(folder, "README.md"), os.path.join(OUT, model + "_README.md"))


if __name__ == "__main__":
    main()
