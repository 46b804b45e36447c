"""Edits of the scene `weathering init` wrote (xml.etree, comments kept).

No bpy here. The scene's format: docs/design.md section 3, xml_scenes/*.xml."""

import copy
import xml.etree.ElementTree as ET


class SceneError(Exception):
    """The generated scene is not what the add-on expects."""


def _number(value):
    return "%.9g" % value


def _triple(v):
    return " ".join(_number(c) for c in v)


def load(path):
    """The scene as an ElementTree, its comments kept (those before the root
    element too: ElementTree has no place for them, they are kept aside)."""
    parser = ET.XMLParser(target=ET.TreeBuilder(insert_comments=True))
    try:
        tree = ET.parse(path, parser)
        with open(path, encoding="utf-8") as f:
            text = f.read()
    except (ET.ParseError, OSError, UnicodeDecodeError) as e:
        raise SceneError("cannot read the generated scene %s: %s" % (path, e))
    start = text.find("<" + tree.getroot().tag)
    preamble = text[:start] if start > 0 else ""
    if preamble.startswith("<?xml"):
        preamble = preamble[preamble.find("?>") + 2:]
    tree.preamble = preamble.strip()
    return tree


def save(tree, path, note=None):
    """Writes the scene (UTF-8), `note` as a comment before its root element."""
    root = tree.getroot()
    ET.indent(tree, space="  ")
    head = ['<?xml version="1.0" encoding="UTF-8"?>']
    if getattr(tree, "preamble", ""):
        head.append(tree.preamble)
    if note:
        head.append("<!-- %s -->" % note.replace("--", "- -"))
    body = ET.tostring(root, encoding="unicode")
    with open(path, "w", encoding="utf-8") as f:
        f.write("\n".join(head) + "\n" + body + "\n")


def output_camera(tree):
    """The <Ortho out="true"> element (init names it 'shot')."""
    for ortho in tree.getroot().iter("Ortho"):
        if ortho.get("out") == "true":
            return ortho
    raise SceneError("the generated scene has no output camera (<Ortho out=\"true\">)")


def set_view(tree, eye, target, up, width, height, resolution):
    """Gives the output camera this <View> (scene axes, Y up); its <OutputMap>
    follows the new map size."""
    ortho = output_camera(tree)
    view = ortho.find("View")
    if view is None:
        raise SceneError("the output camera of the generated scene has no <View>")
    px, py = resolution
    view.set("eye", _triple(eye))
    view.set("target", _triple(target))
    view.set("up", _triple(up))
    view.set("width", _number(width))
    view.set("height", _number(height))
    view.set("resolution", "%d %d" % (px, py))
    output = ortho.find("OutputMap")
    if output is not None:
        for key in ("width", "height"):      # must equal the map size: let it default
            output.attrib.pop(key, None)


def view(tree):
    """The output camera's <View> as {eye, target, up: 3-tuples, width, height,
    resolution: (px, py)}."""
    v = output_camera(tree).find("View")
    floats = lambda key: tuple(float(s) for s in v.get(key).split())
    res = [int(s) for s in v.get("resolution").split()]
    return {"eye": floats("eye"), "target": floats("target"), "up": floats("up"),
            "width": float(v.get("width")), "height": float(v.get("height")),
            "resolution": (res[0], res[-1])}


def output_map_file(tree):
    out = output_camera(tree).find("OutputMap")
    return out.get("file", "mask.exr") if out is not None else None


def _emitters(tree):
    emitters = tree.getroot().find("Emitters")
    return list(emitters) if emitters is not None else []


def _simulation(tree):
    solver = tree.getroot().find("Solver")
    if solver is None:
        solver = ET.SubElement(tree.getroot(), "Solver")
    sim = solver.find("Simulation")
    if sim is None:
        sim = ET.SubElement(solver, "Simulation")
    return sim


def iterations(tree):
    return int(_simulation(tree).get("iterations", "1"))


def set_iterations(tree, n):
    _simulation(tree).set("iterations", str(int(n)))


def particles(tree):
    """Particles over the run: sum of rate * (end - start), times iterations."""
    sim = _simulation(tree)
    duration = float(sim.get("timeStep", "0.01")) * int(sim.get("steps", "1000"))
    total = 0.0
    for e in _emitters(tree):
        if not (isinstance(e.tag, str) and e.tag.endswith("Emitter")):
            continue
        rate = float(e.get("rate", "1000"))
        start = float(e.get("start", "0"))
        end = float(e.get("end", repr(duration)))
        total += rate * max(0.0, end - start)
    return total * iterations(tree)


def scale_particles(tree, factor):
    """Multiplies every emitter's rate by factor."""
    for e in _emitters(tree):
        if isinstance(e.tag, str) and e.tag.endswith("Emitter"):
            e.set("rate", _number(float(e.get("rate", "1000")) * factor))


def set_particles(tree, count):
    """Scales the emitters' rates so that the run emits about `count` particles
    over all its iterations."""
    now = particles(tree)
    if now <= 0:
        raise SceneError("the generated scene emits no particles")
    scale_particles(tree, count / now)


def texture_map_attributes(tree):
    """The attributes of the scene's first <TextureMap> (a dict), or None when
    it has none (`weathering init` leaves it out for a mesh without UVs, or
    whose UV layout covers no texel)."""
    for tex in tree.getroot().iter("TextureMap"):
        return dict(tex.attrib)
    return None


def set_meshes(tree, meshes, resolution=1024):
    """Replaces the <Mesh> of the generated scene by one per object:
    meshes = [(file relative to the scene, TextureMap file or None[,
    TextureMap attributes or None])]. Each keeps the generated <Surface>s; a
    TextureMap takes the attributes given for it (what `init` chose for that
    object alone: its resolution, tiles="udim"...), else the generated one's
    (resolution, padding), or `resolution` when the generated scene has none
    (the combined mesh lacked UVs somewhere), with its own file."""
    geometry = tree.getroot().find("Geometry")
    template = geometry.find("Mesh") if geometry is not None else None
    if template is None:
        raise SceneError("the generated scene has no <Geometry><Mesh>")
    surfaces = [c for c in template if c.tag == "Surface"]
    texture = template.find("TextureMap")
    texture_attrs = dict(texture.attrib) if texture is not None else {"resolution": str(resolution)}
    index = list(geometry).index(template)
    for old in [c for c in geometry if c.tag == "Mesh"]:
        geometry.remove(old)
    for k, entry in enumerate(meshes):
        file, texture_file = entry[0], entry[1]
        own = entry[2] if len(entry) > 2 else None
        mesh = ET.Element("Mesh", {"file": file})
        for s in surfaces:
            mesh.append(copy.deepcopy(s))
        if texture_file:
            attrs = dict(own if own is not None else texture_attrs)
            attrs["file"] = texture_file
            ET.SubElement(mesh, "TextureMap", attrs)
        geometry.insert(index + k, mesh)


def texture_maps(tree):
    """[(mesh file, TextureMap file)] of the scene."""
    found = []
    for mesh in tree.getroot().iter("Mesh"):
        for tex in mesh.findall("TextureMap"):
            found.append((mesh.get("file"), tex.get("file")))
    return found
