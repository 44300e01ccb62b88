#!/usr/bin/python3
"""Publish an occupancy map described by a map_server YAML file.

Usage: map_publisher.py MAP.yaml [--frame FRAME] [ROS remappings]
       map_publisher.py --info MAP.yaml

The YAML file has the map_server keys: image (a PGM file, P5 binary or P2
ASCII, path relative to the YAML file), resolution, origin [x, y, yaw],
negate, occupied_thresh, free_thresh and optionally mode (trinary, scale
or raw).  The grid is latched as nav_msgs/OccupancyGrid on `map` and its
nav_msgs/MapMetaData on `map_metadata`; both names can be remapped.
With --info, no ROS connection is made: the map is loaded and its width,
height, resolution and origin are printed.
"""

import math
import os
import sys


class MapError(Exception):
    """A map YAML or image file that cannot be used."""


def _pgm_tokens(data, count, start):
    """Read COUNT whitespace-separated header tokens of a PGM, skipping comments.

    Returns (tokens, index of the first byte after the last token)."""
    tokens = []
    i = start
    n = len(data)
    while len(tokens) < count:
        while i < n and data[i:i + 1].isspace():
            i += 1
        if i < n and data[i:i + 1] == b'#':
            while i < n and data[i:i + 1] not in (b'\n', b'\r'):
                i += 1
            continue
        j = i
        while j < n and not data[j:j + 1].isspace() and data[j:j + 1] != b'#':
            j += 1
        if j == i:
            raise MapError('truncated PGM header: expected %d numbers, found %d' % (count, len(tokens)))
        tokens.append(data[i:j])
        i = j
    return tokens, i


def read_pgm(path):
    """Read a PGM image (P5 binary or P2 ASCII, 8 or 16 bit).

    Returns (width, height, maxval, pixels) with pixels a list of rows, top
    row first, each a list of integer grey values."""
    try:
        with open(path, 'rb') as f:
            data = f.read()
    except OSError as e:
        raise MapError('cannot read map image %r: %s' % (path, e.strerror))
    magic = data[:2]
    if magic not in (b'P5', b'P2'):
        raise MapError('map image %r is not a PGM file (magic %r, expected P5 or P2)' % (path, magic))
    tokens, pos = _pgm_tokens(data, 3, 2)
    try:
        width, height, maxval = (int(t) for t in tokens)
    except ValueError:
        raise MapError('PGM header of %r has non-numeric size %r' % (path, tokens))
    if width <= 0 or height <= 0 or not 0 < maxval < 65536:
        raise MapError('PGM %r has invalid size %dx%d or maxval %d' % (path, width, height, maxval))
    if magic == b'P5':
        pos += 1  # exactly one whitespace byte ends the header
        bpp = 1 if maxval < 256 else 2
        need = width * height * bpp
        raster = data[pos:pos + need]
        if len(raster) < need:
            raise MapError('PGM %r is truncated: %d pixel bytes, expected %d' % (path, len(raster), need))
        if bpp == 1:
            flat = list(raster)
        else:
            flat = [(raster[k] << 8) | raster[k + 1] for k in range(0, need, 2)]
    else:
        words = data[pos:].split()
        if len(words) < width * height:
            raise MapError('PGM %r is truncated: %d values, expected %d' % (path, len(words), width * height))
        try:
            flat = [int(w) for w in words[:width * height]]
        except ValueError:
            raise MapError('PGM %r has a non-numeric pixel value' % path)
    if any(v > maxval for v in flat):
        raise MapError('PGM %r has pixel values above its maxval %d' % (path, maxval))
    rows = [flat[r * width:(r + 1) * width] for r in range(height)]
    return width, height, maxval, rows


def _number(spec, key, path):
    value = spec.get(key)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise MapError('map YAML %r: %s must be a finite number, got %r' % (path, key, value))
    return float(value)


def load_map_spec(path):
    """Parse a map_server YAML file; returns a dict with the image path made absolute."""
    import yaml
    try:
        with open(path) as f:
            spec = yaml.safe_load(f)
    except OSError as e:
        raise MapError('cannot read map YAML %r: %s' % (path, e.strerror))
    except yaml.YAMLError as e:
        raise MapError('map YAML %r is malformed: %s' % (path, e))
    if not isinstance(spec, dict):
        raise MapError('map YAML %r must be a mapping, got %r' % (path, spec))
    image = spec.get('image')
    if not isinstance(image, str) or not image:
        raise MapError('map YAML %r: image must be a file name, got %r' % (path, image))
    out = {'image': os.path.join(os.path.dirname(os.path.abspath(path)), image)}
    out['resolution'] = _number(spec, 'resolution', path)
    if out['resolution'] <= 0:
        raise MapError('map YAML %r: resolution must be positive, got %r' % (path, out['resolution']))
    origin = spec.get('origin')
    if (not isinstance(origin, list) or len(origin) != 3
            or any(isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v)
                   for v in origin)):
        raise MapError('map YAML %r: origin must be [x, y, yaw], got %r' % (path, origin))
    out['origin'] = [float(v) for v in origin]
    negate = spec.get('negate', 0)
    if negate not in (0, 1, True, False):
        raise MapError('map YAML %r: negate must be 0 or 1, got %r' % (path, negate))
    out['negate'] = bool(negate)
    out['occupied_thresh'] = _number(spec, 'occupied_thresh', path)
    out['free_thresh'] = _number(spec, 'free_thresh', path)
    if not 0.0 <= out['free_thresh'] < out['occupied_thresh'] <= 1.0:
        raise MapError('map YAML %r: need 0 <= free_thresh < occupied_thresh <= 1, got %r and %r'
                       % (path, out['free_thresh'], out['occupied_thresh']))
    mode = spec.get('mode', 'trinary')
    if mode not in ('trinary', 'scale', 'raw'):
        raise MapError('map YAML %r: mode must be trinary, scale or raw, got %r' % (path, mode))
    out['mode'] = mode
    return out


def occupancy_values(spec, maxval, rows):
    """Convert image rows (top first) to occupancy values (bottom row first).

    Values follow map_server: 100 occupied, 0 free, -1 unknown (trinary),
    0..100 between the thresholds (scale), the grey value itself (raw)."""
    occ, free, mode = spec['occupied_thresh'], spec['free_thresh'], spec['mode']
    table = []
    for v in range(maxval + 1):
        if mode == 'raw':
            table.append(v if v <= 127 else v - 256 if v < 256 else -1)
            continue
        p = v / maxval if spec['negate'] else (maxval - v) / maxval
        if p > occ:
            table.append(100)
        elif p < free:
            table.append(0)
        elif mode == 'scale':
            table.append(int(round(99.0 * (p - free) / (occ - free))))
        else:
            table.append(-1)
    values = []
    for row in reversed(rows):
        values.extend(table[v] for v in row)
    return values


def load_map(path):
    """Load a map_server map; returns (spec, width, height, values)."""
    spec = load_map_spec(path)
    width, height, maxval, rows = read_pgm(spec['image'])
    return spec, width, height, occupancy_values(spec, maxval, rows)


def _publish(path, frame):
    import rospy
    from nav_msgs.msg import MapMetaData, OccupancyGrid
    rospy.init_node('map_server')
    try:
        spec, width, height, values = load_map(path)
    except MapError as e:
        rospy.logfatal(str(e))
        sys.exit(1)
    info = MapMetaData()
    info.map_load_time = rospy.Time.now()
    info.resolution = spec['resolution']
    info.width = width
    info.height = height
    x, y, yaw = spec['origin']
    info.origin.position.x = x
    info.origin.position.y = y
    info.origin.orientation.z = math.sin(yaw / 2.0)
    info.origin.orientation.w = math.cos(yaw / 2.0)
    grid = OccupancyGrid()
    grid.header.stamp = info.map_load_time
    grid.header.frame_id = frame
    grid.info = info
    grid.data = values
    meta_pub = rospy.Publisher('map_metadata', MapMetaData, queue_size=1, latch=True)
    map_pub = rospy.Publisher('map', OccupancyGrid, queue_size=1, latch=True)
    meta_pub.publish(info)
    map_pub.publish(grid)
    rospy.loginfo('map %s: %dx%d cells at %.3f m/cell in frame %s',
                  os.path.basename(spec['image']), width, height, spec['resolution'], frame)
    rospy.spin()


def main(argv):
    args = [a for a in argv[1:] if ':=' not in a]
    frame = 'map'
    if '--frame' in args:
        k = args.index('--frame')
        if k + 1 >= len(args):
            sys.exit('map_publisher: --frame needs a frame name')
        frame = args[k + 1]
        del args[k:k + 2]
    info_only = '--info' in args
    args = [a for a in args if a != '--info']
    if len(args) != 1:
        sys.exit('usage: map_publisher.py MAP.yaml [--frame FRAME] | map_publisher.py --info MAP.yaml')
    if info_only:
        try:
            spec, width, height, values = load_map(args[0])
        except MapError as e:
            sys.exit('map_publisher: %s' % e)
        print('width %d height %d resolution %g origin %g %g %g occupied %d free %d unknown %d' % (
            width, height, spec['resolution'], spec['origin'][0], spec['origin'][1], spec['origin'][2],
            sum(1 for v in values if v == 100), values.count(0), values.count(-1)))
        return
    _publish(args[0], frame)


if __name__ == '__main__':
    main(sys.argv)
