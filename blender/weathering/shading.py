"""The results in the materials: image nodes for the texture's channels, the
camera mask as a projection, and a mix of the main channel into the shader.

Every node the add-on adds is named "weathering:..." so that a second run
replaces them (and restores the links they took) instead of stacking up."""

import array

import bpy

PREFIX = "weathering:"

# What the mix shows, per preset: the channel to mix (first present), the colour.
LOOKS = {
    "rain": (("dirt", "Y"), (0.10, 0.085, 0.07, 1.0)),
    "dust": (("dirt", "Y"), (0.62, 0.53, 0.40, 1.0)),
    "soot": (("dirt", "Y"), (0.015, 0.014, 0.013, 1.0)),
    "moss": (("mossy", "moss", "Y"), (0.10, 0.20, 0.04, 1.0)),
    "rust": (("rust", "Y"), (0.35, 0.12, 0.04, 1.0)),
    "old_paint": (("peel", "crack", "Y"), (0.30, 0.28, 0.26, 1.0)),
}


def main_channel(preset, names):
    """The channel to mix in: the preset's first that exists, else the first
    that is not 'seen', else None."""
    for name in LOOKS.get(preset, LOOKS["rain"])[0]:
        if name in names:
            return name
    rest = [n for n in names if n != "seen"]
    return rest[0] if rest else None


def load_image(path):
    """An EXR as a Non-Color image, reloaded if it was loaded before."""
    image = bpy.data.images.load(path, check_existing=True)
    image.reload()
    image.colorspace_settings.name = "Non-Color"
    return image


UDIM = "<UDIM>"


def load_tiles(pattern, numbers):
    """A UDIM set as one tiled Non-Color image (Blender 3.4: source 'TILED',
    the <UDIM> token in its filepath): `pattern` is the files' path with <UDIM>
    where the tile number stands, `numbers` the tiles (1001, 1002, ...). An
    image of an earlier run with the same pattern is reused and reloaded."""
    image = None
    for im in bpy.data.images:
        if im.source == "TILED" and bpy.path.abspath(im.filepath) == pattern:
            image = im
            break
    if image is None:
        image = bpy.data.images.load(pattern.replace(UDIM, str(numbers[0])), check_existing=False)
        image.source = "TILED"
        image.filepath = pattern
        image.name = bpy.path.basename(pattern)
    have = {t.number for t in image.tiles}
    for n in numbers:
        if n not in have:
            image.tiles.new(tile_number=n)
    image.reload()                      # every tile's file, found through the token
    image.colorspace_settings.name = "Non-Color"
    return image


def _image_values(image, step=7):
    w, h = image.size
    if w * h == 0:
        return []
    pixels = array.array("f", bytes(4 * 4 * w * h))
    image.pixels.foreach_get(pixels)
    return [v for v in pixels[0::4 * step] if v > 0.0]


def fully_dirty(image, percentile=0.95):
    """The amount the mix calls fully dirty: the `percentile` of the image's
    positive values (every 7th texel; of every tile of a UDIM image), or 1
    when none is positive."""
    if image.source == "TILED":
        # Blender's pixels are the first tile's: read each tile's file alone.
        values = []
        pattern = bpy.path.abspath(image.filepath)
        for tile in image.tiles:
            one = bpy.data.images.load(pattern.replace(UDIM, str(tile.number)),
                                       check_existing=False)
            values += _image_values(one)
            bpy.data.images.remove(one)
    else:
        values = _image_values(image)
    values.sort()
    if not values:
        return 1.0
    return max(values[int(percentile * (len(values) - 1))], 1e-12)


def _ours(node):
    return node.name.startswith(PREFIX)


def clear(mat):
    """Removes the add-on's nodes from mat, giving back the links they took."""
    if not mat.use_nodes or mat.node_tree is None:
        return
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    mix = nodes.get(PREFIX + "mix")
    if mix is not None:
        targets = [l.to_socket for l in mix.outputs[0].links if not _ours(l.to_node)]
        if mix.bl_idname == "ShaderNodeMixShader":
            source = mix.inputs[1].links[0].from_socket if mix.inputs[1].links else None
            for socket in targets:
                if source is not None:
                    links.new(source, socket)
        else:
            color1 = mix.inputs["Color1"]
            source = color1.links[0].from_socket if color1.links else None
            for socket in targets:
                if source is not None and not _ours(source.node):
                    links.new(source, socket)
                elif hasattr(socket, "default_value"):
                    socket.default_value = color1.default_value
    for node in [n for n in nodes if _ours(n)]:
        nodes.remove(node)


def _new(nodes, kind, name, label, location):
    node = nodes.new(kind)
    node.name = PREFIX + name
    node.label = label
    node.location = location
    return node


def _surface_shader(mat):
    output = mat.node_tree.get_output_node("ALL")
    if output is None:
        output = mat.node_tree.nodes.new("ShaderNodeOutputMaterial")
    surface = output.inputs["Surface"]
    shader = surface.links[0].from_node if surface.links else None
    return output, shader


def project_mask(nodes, links, image, ndc, location):
    """docs/mask.md's projection: an Image Texture node reading `image` at the
    point's position through the output camera's worldToNDC (16 numbers, row
    by row, scene axes); Blender's world (X, Y, Z) is the scene's (X, Z, -Y)."""
    m = [ndc[0:4], ndc[4:8], ndc[8:12], ndc[12:16]]
    x0, y0 = location
    geometry = _new(nodes, "ShaderNodeNewGeometry", "mask_position", "Position", (x0 - 800, y0))

    def coordinate(column, y):
        # [x y z 1] * M[:, c] with (x, y, z) = (X, Z, -Y): X*m0c - Y*m2c + Z*m1c + m3c
        dot = _new(nodes, "ShaderNodeVectorMath", "mask_dot%d" % column, "", (x0 - 600, y))
        dot.operation = "DOT_PRODUCT"
        dot.inputs[1].default_value = (m[0][column], -m[2][column], m[1][column])
        links.new(geometry.outputs["Position"], dot.inputs[0])
        add = _new(nodes, "ShaderNodeMath", "mask_add%d" % column, "", (x0 - 420, y))
        add.operation = "ADD"
        add.inputs[1].default_value = m[3][column]
        links.new(dot.outputs["Value"], add.inputs[0])
        return add

    u = coordinate(0, y0)
    flip = _new(nodes, "ShaderNodeMath", "mask_flip", "v = 1 - y_ndc", (x0 - 250, y0 - 150))
    flip.operation = "SUBTRACT"
    flip.inputs[0].default_value = 1.0
    links.new(coordinate(1, y0 - 150).outputs[0], flip.inputs[1])
    uv = _new(nodes, "ShaderNodeCombineXYZ", "mask_uv", "mask UV", (x0 - 120, y0))
    links.new(u.outputs[0], uv.inputs["X"])
    links.new(flip.outputs[0], uv.inputs["Y"])
    tex = _new(nodes, "ShaderNodeTexImage", "mask", "", (x0, y0))
    tex.image = image
    tex.interpolation = "Closest"       # no blur across the mask's silhouettes
    tex.extension = "CLIP"              # 0 outside the output camera's frame
    links.new(uv.outputs["Vector"], tex.inputs["Vector"])
    return tex


def weather(mat, uv_map, channels, main, mask, colour, full):
    """Adds to mat: a UV Map node naming uv_map, an Image Texture node per
    (channel, image) of `channels` labelled by the channel; the projected mask
    when `mask` = (channel, image, worldToNDC) is given; and a mix of `main`
    (a channel name of `channels`, or "mask" for the projection) into the base
    colour of the surface shader (Principled BSDF: a Mix RGB on its Base Color;
    another shader: a Mix Shader with a dirt-coloured Principled BSDF),
    through a Map Range from [0, full] to [0, 1]. Returns {label: node}."""
    mat.use_nodes = True
    clear(mat)
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    output, shader = _surface_shader(mat)
    x0 = (shader.location.x if shader is not None else output.location.x) - 700
    y0 = (shader.location.y if shader is not None else output.location.y) + 200
    added = {}
    if channels:
        uv = _new(nodes, "ShaderNodeUVMap", "uv", "UV " + (uv_map or ""), (x0 - 500, y0))
        uv.uv_map = uv_map or ""
        for k, (name, image) in enumerate(channels):
            tex = _new(nodes, "ShaderNodeTexImage", "texture_" + name, name,
                       (x0 - 250, y0 - 280 * k))
            tex.image = image
            tex.interpolation = "Linear"
            tex.extension = "EXTEND"
            links.new(uv.outputs["UV"], tex.inputs["Vector"])
            added[name] = tex
    if mask is not None:
        name, image, ndc = mask
        tex = project_mask(nodes, links, image, ndc, (x0 - 250, y0 - 280 * len(channels) - 100))
        tex.label = "mask %s (shot)" % name
        added["mask"] = tex
    source = added.get(main)
    if source is None:
        return added
    ramp = _new(nodes, "ShaderNodeMapRange", "map_range", "0 .. fully dirty", (x0, y0 + 250))
    ramp.clamp = True
    ramp.inputs["From Min"].default_value = 0.0
    ramp.inputs["From Max"].default_value = full
    links.new(source.outputs["Color"], ramp.inputs["Value"])
    if shader is not None and shader.bl_idname == "ShaderNodeBsdfPrincipled":
        base = shader.inputs["Base Color"]
        mix = _new(nodes, "ShaderNodeMixRGB", "mix", "weathering", (x0 + 220, y0 + 250))
        mix.blend_type = "MIX"
        if base.links:
            links.new(base.links[0].from_socket, mix.inputs["Color1"])
        mix.inputs["Color1"].default_value = base.default_value
        mix.inputs["Color2"].default_value = colour
        links.new(ramp.outputs["Result"], mix.inputs["Fac"])
        links.new(mix.outputs["Color"], base)
    else:
        dirt = _new(nodes, "ShaderNodeBsdfPrincipled", "dirt_shader", "dirt", (x0 + 220, y0 - 300))
        dirt.inputs["Base Color"].default_value = colour
        dirt.inputs["Roughness"].default_value = 0.9
        mix = _new(nodes, "ShaderNodeMixShader", "mix", "weathering", (output.location.x - 200,
                                                                        output.location.y))
        if shader is not None:
            links.new(output.inputs["Surface"].links[0].from_socket, mix.inputs[1])
        links.new(ramp.outputs["Result"], mix.inputs["Fac"])
        links.new(dirt.outputs["BSDF"], mix.inputs[2])
        links.new(mix.outputs["Shader"], output.inputs["Surface"])
    added["mix"] = mix
    return added
