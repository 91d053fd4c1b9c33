"""The x, y of every point record of an uncompressed LAS file (1.0-1.4), in CRS units: the
reference the CLI tests count a region's points against. Standard library only."""
import struct


def las_xy(path):
    with open(path, "rb") as f:
        data = f.read()
    minor = data[25]
    offset = struct.unpack_from("<I", data, 96)[0]
    length = struct.unpack_from("<H", data, 105)[0]
    count = struct.unpack_from("<I", data, 107)[0]
    if minor >= 4 and count == 0:  # LAS 1.4: the 64-bit count
        count = struct.unpack_from("<Q", data, 247)[0]
    scale = struct.unpack_from("<3d", data, 131)
    origin = struct.unpack_from("<3d", data, 155)
    out = []
    for i in range(count):
        x, y, _ = struct.unpack_from("<3i", data, offset + i * length)
        out.append((x * scale[0] + origin[0], y * scale[1] + origin[1]))
    return out


def count_in_cells(points, cell, halo, first, last):
    """Points inside cells first..last (column, row) of a grid of `cell` from the origin,
    grown by `halo` (bounds inclusive): what a fit job of those cells reads."""
    x0, y0 = first[0] * cell - halo, first[1] * cell - halo
    x1, y1 = (last[0] + 1) * cell + halo, (last[1] + 1) * cell + halo
    return sum(1 for x, y in points if x0 <= x <= x1 and y0 <= y <= y1)
