#!/usr/bin/python3
"""List what robot_state_publisher and joint_state_publisher make of a URDF.

Usage: urdf_frames.py URDF (name|root|links|joints) [--prefix PREFIX]

  name    the robot name
  root    the root link (with PREFIX/ in front when given)
  links   every link that gets a TF frame, one a line (links below a floating
          or planar joint get none), with PREFIX/ in front when given
  joints  every joint joint_state_publisher publishes: revolute, continuous and
          prismatic joints that do not mimic another joint
"""

import sys
import xml.etree.ElementTree as ET


def describe(path):
    """Return (name, root, tf_links, published_joints) of the URDF at PATH."""
    try:
        robot = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as e:
        raise ValueError('cannot read URDF %r: %s' % (path, e))
    if robot.tag != 'robot':
        raise ValueError('URDF %r: root element is <%s>, expected <robot>' % (path, robot.tag))
    links = [l.get('name') for l in robot.findall('link')]
    parent_of, joint_type, published = {}, {}, []
    for j in robot.findall('joint'):
        parent, child = j.find('parent'), j.find('child')
        if parent is None or child is None:
            raise ValueError('URDF %r: joint %r lacks a parent or child' % (path, j.get('name')))
        parent_of[child.get('link')] = parent.get('link')
        joint_type[child.get('link')] = j.get('type')
        if j.get('type') in ('revolute', 'continuous', 'prismatic') and j.find('mimic') is None:
            published.append(j.get('name'))
    roots = [l for l in links if l not in parent_of]
    if len(roots) != 1:
        raise ValueError('URDF %r: expected one root link, found %r' % (path, roots))

    def has_tf(link):
        while link in parent_of:
            if joint_type[link] in ('floating', 'planar'):
                return False
            link = parent_of[link]
        return True

    return robot.get('name'), roots[0], [l for l in links if has_tf(l)], published


def main(argv):
    args = argv[1:]
    prefix = ''
    if '--prefix' in args:
        k = args.index('--prefix')
        if k + 1 >= len(args):
            sys.exit('urdf_frames: --prefix needs a value')
        prefix = args[k + 1].strip('/') + '/'
        del args[k:k + 2]
    if len(args) != 2 or args[1] not in ('name', 'root', 'links', 'joints'):
        sys.exit(__doc__)
    try:
        name, root, links, joints = describe(args[0])
    except ValueError as e:
        sys.exit('urdf_frames: %s' % e)
    if args[1] == 'name':
        print(name)
    elif args[1] == 'root':
        print(prefix + root)
    elif args[1] == 'links':
        print('\n'.join(prefix + l for l in links))
    else:
        print('\n'.join(joints))


if __name__ == '__main__':
    main(sys.argv)
