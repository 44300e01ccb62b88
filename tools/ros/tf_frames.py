#!/usr/bin/python3
"""Print the TF tree edges seen on /tf and /tf_static.

Usage: tf_frames.py [SECONDS] [--require FRAME ...] [--chain FROM TO]

Listens for SECONDS (default 2.0) and prints one line per edge,
`static|dynamic PARENT CHILD`, sorted.  With --require, exits with status 1
naming every FRAME that appeared in no edge.  With --chain, exits with
status 1 unless FROM is connected to TO through the edges seen (FROM an
ancestor of TO).
"""

import sys
import threading


def main(argv):
    args = argv[1:]
    seconds = 2.0
    required = []
    chains = []
    i = 0
    while i < len(args):
        a = args[i]
        if a == '--require':
            i += 1
            while i < len(args) and not args[i].startswith('--'):
                required.append(args[i])
                i += 1
            continue
        if a == '--chain':
            if i + 2 >= len(args):
                sys.exit('tf_frames: --chain needs FROM and TO frames')
            chains.append((args[i + 1], args[i + 2]))
            i += 3
            continue
        try:
            seconds = float(a)
        except ValueError:
            sys.exit('tf_frames: expected a number of seconds, --require or --chain, got %r' % a)
        if not seconds > 0:
            sys.exit('tf_frames: seconds must be positive, got %r' % a)
        i += 1

    import rospy
    from tf2_msgs.msg import TFMessage
    edges = {}
    lock = threading.Lock()

    def collector(kind):
        def callback(message):
            with lock:
                for t in message.transforms:
                    edges[(t.header.frame_id.lstrip('/'), t.child_frame_id.lstrip('/'))] = kind
        return callback

    rospy.init_node('tf_frames', anonymous=True, disable_signals=True)
    rospy.Subscriber('/tf', TFMessage, collector('dynamic'), queue_size=100)
    rospy.Subscriber('/tf_static', TFMessage, collector('static'), queue_size=100)
    rospy.sleep(seconds)
    with lock:
        seen = dict(edges)
    rospy.signal_shutdown('done')
    for (parent, child), kind in sorted(seen.items()):
        print('%s %s %s' % (kind, parent, child))
    failed = False
    frames = set(p for p, _ in seen) | set(c for _, c in seen)
    for frame in required:
        if frame not in frames:
            print('MISSING frame %s' % frame)
            failed = True
    parent_of = dict((c, p) for p, c in seen)
    for start, end in chains:
        node, hops = end, 0
        while node != start and node in parent_of and hops <= len(parent_of):
            node, hops = parent_of[node], hops + 1
        if node != start:
            print('MISSING chain %s -> %s' % (start, end))
            failed = True
    sys.exit(1 if failed else 0)


if __name__ == '__main__':
    main(sys.argv)
