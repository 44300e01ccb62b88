#!/usr/bin/python3
"""Compare the forward kinematics of robots/pr2/pr2.urdf with the real PR2 URDF.

For N seeded random joint configurations within the joint limits, the poses of
the tool and camera frames (relative to base_footprint) of both models must
agree within 1 mm and 0.001 rad.  Prints the maximum errors; exits 1 on a
mismatch, 2 on unusable input, and 0 with a message when the reference is absent.

usage: fk_check.py [--samples N] [--seed S] [--authored PATH] [--reference PATH ...]
"""

import math
import os
import random
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import urdfmodel  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, "..", ".."))
SHARED = os.path.normpath(os.path.join(REPO, "..", "shared", "models", "pr2_description", "urdf"))
DEFAULT_REFERENCES = [os.path.join(SHARED, "pr2.urdf"), os.path.join(SHARED, "pr2_kinect1.urdf")]
PEPPER_AUTHORED = os.path.join(REPO, "robots", "pepper", "pepper.urdf")
PEPPER_REFERENCE = os.path.normpath(os.path.join(REPO, "..", "shared", "models", "pepper_description",
                                                 "urdf", "pepper.urdf"))
PEPPER_FRAMES = ["l_gripper", "r_gripper", "LThumb1_link", "RThumb1_link", "CameraTop_optical_frame",
                 "CameraBottom_optical_frame", "CameraDepth_optical_frame", "Head", "base_footprint",
                 "Tablet_frame"]
FRAMES = ["l_gripper_tool_frame", "r_gripper_tool_frame", "narrow_stereo_optical_frame",
          "head_mount_kinect_rgb_optical_frame", "head_mount_kinect_rgb_link", "head_mount_prosilica_link",
          "head_plate_frame", "l_wrist_roll_link", "r_wrist_roll_link",
          "l_gripper_l_finger_tip_link", "r_gripper_r_finger_tip_link", "base_laser_link",
          "laser_tilt_mount_link", "torso_lift_link"]
POS_TOL = 1e-3
ROT_TOL = 1e-3


def random_configuration(model, rng):
    values = {}
    for j in sorted(model.movable_joints(), key=lambda j: j.name):
        if j.type == "continuous":
            values[j.name] = rng.uniform(-math.pi, math.pi)
        else:
            values[j.name] = rng.uniform(j.lower, j.upper)
    return values


def compare(authored, reference, samples, seed, wanted=None):
    """Return (frames compared, max position error, max rotation error, worst frame)."""
    frames = [f for f in (wanted or FRAMES) if f in authored.links and f in reference.links]
    if not frames:
        raise ValueError("no common tool or camera frames between the two models")
    rng = random.Random(seed)
    max_p, max_r, worst = 0.0, 0.0, None
    for _ in range(samples):
        values = random_configuration(authored, rng)
        pa = authored.link_poses(values)
        pr = reference.link_poses(values)
        for f in frames:
            a, b = pa[f], pr[f]
            dp = math.sqrt(sum((a[i][3] - b[i][3]) ** 2 for i in range(3)))
            dr = urdfmodel.rotation_angle_between(a, b)
            if dp > max_p or dr > max_r:
                worst = f
            max_p, max_r = max(max_p, dp), max(max_r, dr)
    return frames, max_p, max_r, worst


def main(argv):
    samples, seed = 1000, 20240611
    authored_path = os.path.join(REPO, "robots", "pr2", "pr2.urdf")
    refs = []
    args = list(argv[1:])
    while args:
        a = args.pop(0)
        if a == "--samples":
            samples = int(args.pop(0))
        elif a == "--seed":
            seed = int(args.pop(0))
        elif a == "--authored":
            authored_path = args.pop(0)
        elif a == "--reference":
            refs.append(args.pop(0))
        else:
            sys.stderr.write("fk_check: unknown argument %r\n" % a)
            return 2
    refs = refs or DEFAULT_REFERENCES
    present = [r for r in refs if os.path.exists(r)]
    if not present:
        print("fk_check: SKIP, no reference PR2 URDF at %s" % ", ".join(refs))
        return 0
    try:
        authored = urdfmodel.load(authored_path)
    except (OSError, ValueError) as e:
        sys.stderr.write("fk_check: cannot load %s: %s\n" % (authored_path, e))
        return 2
    ok = True
    for ref_path in present:
        reference = urdfmodel.load(ref_path)
        frames, max_p, max_r, worst = compare(authored, reference, samples, seed)
        good = max_p <= POS_TOL and max_r <= ROT_TOL
        ok = ok and good
        print("fk_check: %s vs %s: %d configurations, %d frames (%s)"
              % (os.path.basename(authored_path), os.path.basename(ref_path), samples,
                 len(frames), " ".join(frames)))
        print("fk_check:   max position error %.3e m, max rotation error %.3e rad%s -> %s"
              % (max_p, max_r, (" (worst %s)" % worst) if worst else "",
                 "ok" if good else "FAIL"))
    if "--authored" not in argv and "--reference" not in argv:
        ok = check_pepper(samples, seed) and ok
    return 0 if ok else 1


def check_pepper(samples, seed):
    """Same comparison for the authored Pepper (hand, camera and base frames)."""
    if not os.path.exists(PEPPER_REFERENCE):
        print("fk_check: SKIP pepper, no reference at %s" % PEPPER_REFERENCE)
        return True
    authored = urdfmodel.load(PEPPER_AUTHORED)
    reference = urdfmodel.load(PEPPER_REFERENCE)
    frames, max_p, max_r, worst = compare(authored, reference, samples, seed, PEPPER_FRAMES)
    good = max_p <= POS_TOL and max_r <= ROT_TOL and len(frames) == len(PEPPER_FRAMES)
    print("fk_check: pepper.urdf vs reference pepper.urdf: %d configurations, %d frames"
          % (samples, len(frames)))
    print("fk_check:   max position error %.3e m, max rotation error %.3e rad -> %s"
          % (max_p, max_r, "ok" if good else "FAIL"))
    return good


if __name__ == "__main__":
    sys.exit(main(sys.argv))
