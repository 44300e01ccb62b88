#!/usr/bin/python3
"""Latch static transforms on /tf_static.

Usage: static_tf_publisher.py X Y Z YAW PITCH ROLL FRAME CHILD [X Y Z ... ] [ROS remappings]
       static_tf_publisher.py X Y Z QX QY QZ QW FRAME CHILD [...]

Each transform is given with the argument order of tf2's
static_transform_publisher: translation in metres, then either yaw,
pitch and roll in radians or a quaternion (x y z w), then the parent and
the child frame.  Several transforms may follow one another; they are
published together in one latched tf2_msgs/TFMessage.
"""

import math
import sys


class TransformError(Exception):
    """Command-line arguments that do not describe transforms."""


def _finite(word):
    try:
        value = float(word)
    except ValueError:
        raise TransformError('expected a number, got %r' % word)
    if not math.isfinite(value):
        raise TransformError('expected a finite number, got %r' % word)
    return value


def _is_number(word):
    try:
        float(word)
        return True
    except ValueError:
        return False


def quaternion_from_ypr(yaw, pitch, roll):
    """Quaternion (x, y, z, w) of a rotation by yaw about z, then pitch about y, then roll about x."""
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    return (sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
            cr * cp * cy + sr * sp * sy)


def parse_transforms(words):
    """Parse argument words into a list of (parent, child, (x, y, z), (qx, qy, qz, qw))."""
    out = []
    i = 0
    while i < len(words):
        k = i
        while k < len(words) and _is_number(words[k]):
            k += 1
        numbers = [_finite(w) for w in words[i:k]]
        if len(numbers) not in (6, 7):
            raise TransformError('transform %d: expected 6 (x y z yaw pitch roll) or 7 (x y z qx qy qz qw) '
                                 'numbers before the frame names, got %d: %r'
                                 % (len(out) + 1, len(numbers), words[i:k]))
        if k + 2 > len(words):
            raise TransformError('transform %d: expected a parent and a child frame after %r'
                                 % (len(out) + 1, words[i:k]))
        parent, child = words[k].lstrip('/'), words[k + 1].lstrip('/')
        if not parent or not child or parent == child:
            raise TransformError('transform %d: parent %r and child %r must be two different frame names'
                                 % (len(out) + 1, words[k], words[k + 1]))
        if len(numbers) == 6:
            q = quaternion_from_ypr(*numbers[3:6])
        else:
            norm = math.sqrt(sum(c * c for c in numbers[3:7]))
            if norm < 1e-9:
                raise TransformError('transform %d: quaternion %r has zero length' % (len(out) + 1, numbers[3:7]))
            q = tuple(c / norm for c in numbers[3:7])
        out.append((parent, child, tuple(numbers[0:3]), q))
        i = k + 2
    if not out:
        raise TransformError('no transform given')
    return out


def main(argv):
    words = [a for a in argv[1:] if ':=' not in a]
    try:
        transforms = parse_transforms(words)
    except TransformError as e:
        sys.exit('static_tf_publisher: %s\n%s' % (e, __doc__))
    import rospy
    from geometry_msgs.msg import TransformStamped
    from tf2_msgs.msg import TFMessage
    rospy.init_node('static_tf_publisher', anonymous=True)
    stamp = rospy.Time.now()
    message = TFMessage()
    for parent, child, (x, y, z), (qx, qy, qz, qw) in transforms:
        t = TransformStamped()
        t.header.stamp = stamp
        t.header.frame_id = parent
        t.child_frame_id = child
        t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = x, y, z
        (t.transform.rotation.x, t.transform.rotation.y,
         t.transform.rotation.z, t.transform.rotation.w) = qx, qy, qz, qw
        message.transforms.append(t)
    publisher = rospy.Publisher('/tf_static', TFMessage, queue_size=1, latch=True)
    publisher.publish(message)
    rospy.loginfo('static transforms: %s',
                  ', '.join('%s -> %s' % (p, c) for p, c, _, _ in transforms))
    rospy.spin()


if __name__ == '__main__':
    main(sys.argv)
