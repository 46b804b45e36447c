"""The header of a mask: the output camera's matrices (docs/mask.md, "The header").

Pure Python (Blender has no OpenEXR module, Debian's no numpy either)."""

import struct

_MAGIC = b"\x76\x2f\x31\x01"
_HEADER_LIMIT = 1 << 20          # headers are a few hundred bytes; refuse more


def read_header(path):
    """Attributes of a single-part EXR as {name: (type, value)}: m44f as 16
    floats (row by row, applied to row vectors), box2i as (xmin, ymin, xmax,
    ymax), string as str, any other type as raw bytes. Raises ValueError."""
    with open(path, "rb") as f:
        data = f.read(_HEADER_LIMIT)
    if data[:4] != _MAGIC:
        raise ValueError("%s is not an OpenEXR file" % path)
    version = struct.unpack_from("<i", data, 4)[0]
    if version & 0xFF != 2 or version & (1 << 12 | 1 << 13):
        raise ValueError("%s: version field %#x, expected a single-part file" % (path, version))
    pos = 8
    attributes = {}

    def cstring():
        nonlocal pos
        end = data.index(b"\0", pos)
        text = data[pos:end].decode("latin-1")
        pos = end + 1
        return text

    try:
        while True:
            name = cstring()
            if not name:
                return attributes
            kind = cstring()
            size = struct.unpack_from("<i", data, pos)[0]
            pos += 4
            raw = data[pos:pos + size]
            if size < 0 or len(raw) != size:
                raise ValueError("%s: header cut short in %s" % (path, name))
            pos += size
            if kind == "m44f" and size == 64:
                value = list(struct.unpack("<16f", raw))
            elif kind == "box2i" and size == 16:
                value = struct.unpack("<4i", raw)
            elif kind == "string":
                value = raw.decode("utf-8", "replace")
            else:
                value = raw
            attributes[name] = (kind, value)
    except (struct.error, ValueError) as e:
        if isinstance(e, ValueError) and str(e).startswith(path):
            raise
        raise ValueError("%s: unreadable header" % path)


def matrix(attributes, name):
    """The 16 numbers of an m44f attribute, or None."""
    kind, value = attributes.get(name, (None, None))
    return value if kind == "m44f" else None


def size(attributes):
    """(width, height) of the data window, or None."""
    kind, value = attributes.get("dataWindow", (None, None))
    if kind != "box2i":
        return None
    return value[2] - value[0] + 1, value[3] - value[1] + 1
