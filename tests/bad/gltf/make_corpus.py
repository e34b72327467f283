#!/usr/bin/env python3
"""Writes the broken glTF corpus (run from this folder). The expected messages are in
tests/scene_bad_gltf.rs. Kept so the files can be regenerated; the files are committed."""
import base64, json, struct

TRI = [0, 0, 0, 1, 0, 0, 0, 1, 0]


def b64(data):
    return "data:application/octet-stream;base64," + base64.b64encode(data).decode()


def doc(positions=TRI, indices=None, mode=None, buffer_uri=None, pos_count=None, extra=None,
        index_type=5123, raw_bin=None):
    pos = struct.pack("<%df" % len(positions), *positions)
    bin_ = bytearray(pos)
    views = [{"buffer": 0, "byteOffset": 0, "byteLength": len(pos)}]
    accessors = [{"bufferView": 0, "componentType": 5126,
                  "count": pos_count if pos_count is not None else len(positions) // 3, "type": "VEC3"}]
    prim = {"attributes": {"POSITION": 0}}
    if indices is not None:
        while len(bin_) % 4:
            bin_.append(0)
        fmt = "<%dH" % len(indices) if index_type == 5123 else "<%dI" % len(indices)
        ib = struct.pack(fmt, *indices)
        views.append({"buffer": 0, "byteOffset": len(bin_), "byteLength": len(ib)})
        bin_ += ib
        accessors.append({"bufferView": 1, "componentType": index_type, "count": len(indices), "type": "SCALAR"})
        prim["indices"] = 1
    if mode is not None:
        prim["mode"] = mode
    if raw_bin is not None:
        bin_ = raw_bin
    d = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "tri_node", "mesh": 0}],
        "meshes": [{"name": "tri", "primitives": [prim]}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(bin_), "uri": buffer_uri or b64(bytes(bin_))}],
    }
    if extra:
        extra(d)
    return d


def write(name, d):
    with open(name, "w") as f:
        json.dump(d, f, indent=1)


write("missing_buffer.gltf", doc(buffer_uri="nope.bin"))
write("accessor_out_of_bounds.gltf", doc(pos_count=100))
def view_oob(d): d["bufferViews"][0]["byteLength"] = 4096
write("buffer_view_out_of_bounds.gltf", doc(extra=view_oob))
write("index_past_vertex_count.gltf", doc(indices=[0, 1, 7]))
write("index_past_vertex_count_u32.gltf", doc(indices=[0, 1, 2, 2, 1, 70000], index_type=5125))
write("nan_position.gltf", doc(positions=[0, 0, 0, float("nan"), 0, 0, 0, 1, 0]))
write("inf_position.gltf", doc(positions=[0, 0, 0, 1, 0, 0, 0, float("inf"), 0]))
def lines(d):
    d["meshes"][0]["primitives"].append({"attributes": {"POSITION": 0}, "mode": 1})
write("lines_primitive.gltf", doc(extra=lines))
def points_only(d): d["meshes"][0]["primitives"][0]["mode"] = 0
write("points_only.gltf", doc(extra=points_only))
def draco(d):
    d["extensionsUsed"] = ["KHR_draco_mesh_compression"]
    d["extensionsRequired"] = ["KHR_draco_mesh_compression"]
write("unsupported_required_extension.gltf", doc(extra=draco))
def absurd_count(d): d["accessors"][0]["count"] = 4000000000
write("absurd_accessor_count.gltf", doc(extra=absurd_count))
def absurd_buffer(d): d["buffers"][0]["byteLength"] = 10**15
write("absurd_buffer_length.gltf", doc(extra=absurd_buffer))
def bad_ref(d): d["meshes"][0]["primitives"][0]["attributes"]["NORMAL"] = 9
write("dangling_accessor_reference.gltf", doc(extra=bad_ref))
def cycle(d):
    d["nodes"] = [{"name": "a", "children": [1]}, {"name": "b", "children": [0], "mesh": 0}]
write("node_cycle.gltf", doc(extra=cycle))
def inf_node(d): d["nodes"][0]["translation"] = [1e39, 0, 0]
write("inf_node_transform.gltf", doc(extra=inf_node))
def neg_range(d):
    d["extensionsUsed"] = ["KHR_lights_punctual"]
    d["extensions"] = {"KHR_lights_punctual": {"lights": [{"name": "lamp", "type": "point", "range": -1.0}]}}
    d["nodes"].append({"name": "lamp_node", "extensions": {"KHR_lights_punctual": {"light": 0}}})
    d["scenes"][0]["nodes"].append(1)
write("light_negative_range.gltf", doc(extra=neg_range))
def huge_light(d):
    d["extensionsUsed"] = ["KHR_lights_punctual"]
    d["extensions"] = {"KHR_lights_punctual": {"lights": [{"name": "sun", "type": "point", "intensity": 1e39, "range": 2}]}}
    d["nodes"].append({"name": "lamp_node", "extensions": {"KHR_lights_punctual": {"light": 0}}})
    d["scenes"][0]["nodes"].append(1)
write("light_infinite_intensity.gltf", doc(extra=huge_light))
def missing_tex(d):
    d["images"] = [{"uri": "no_such_image.png"}]
    d["textures"] = [{"source": 0}]
    d["materials"] = [{"name": "painted", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]
    d["meshes"][0]["primitives"][0]["material"] = 0
write("missing_texture.gltf", doc(extra=missing_tex))
write("bad_base64.gltf", doc(buffer_uri="data:application/octet-stream;base64,@@@@"))
def short_buffer(d): d["buffers"][0]["byteLength"] = 1000
write("buffer_shorter_than_declared.gltf", doc(extra=short_buffer))
def sparse(d):
    # The index is read from the bytes of 1.0f: far past the 3 elements.
    d["accessors"][0]["sparse"] = {"count": 1, "indices": {"bufferView": 0, "byteOffset": 12,
                                                           "componentType": 5125},
                                    "values": {"bufferView": 0}}
write("sparse_accessor.gltf", doc(extra=sparse))
def vec2_pos(d): d["accessors"][0]["type"] = "VEC2"
write("position_wrong_type.gltf", doc(extra=vec2_pos))
with open("bad_json.gltf", "w") as f:
    f.write('{\n  "asset": {"version": "2.0"},\n  "nodes": [ {"mesh": 0,} ]\n}\n')
# GLB whose buffer refers to the BIN chunk, but there is none.
js = json.dumps({"asset": {"version": "2.0"}, "buffers": [{"byteLength": 12}],
                 "bufferViews": [{"buffer": 0, "byteLength": 12}]}).encode()
js += b" " * ((4 - len(js) % 4) % 4)
glb = b"glTF" + struct.pack("<II", 2, 12 + 8 + len(js)) + struct.pack("<I", len(js)) + b"JSON" + js
open("glb_without_bin_chunk.glb", "wb").write(glb)
open("truncated.glb", "wb").write(glb[:30])
# Not a tree: each level's two nodes both have the next level's two nodes as children, so
# 2^40 node instances are reachable.
def explosion(d):
    levels = 40
    nodes = []
    for i in range(levels):
        kids = [2 * (i + 1), 2 * (i + 1) + 1] if i + 1 < levels else []
        nodes.append({"name": "a%d" % i, "children": kids})
        nodes.append({"name": "b%d" % i, "children": kids, "mesh": 0} if not kids else {"name": "b%d" % i, "children": kids})
    d["nodes"] = nodes
    d["scenes"][0]["nodes"] = [0]
write("node_instance_explosion.gltf", doc(extra=explosion))
