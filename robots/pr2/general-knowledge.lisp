;;;; PR2: frames, torso and location costmap metadata.

(in-package :cram-pr2-description)

(def-fact-group pr2-metadata (robot robot-odom-frame robot-base-frame robot-base-link
                              robot-torso-link-joint)
  (<- (robot :pr2))

  (<- (robot-odom-frame :pr2 "odom_combined"))
  (<- (robot-base-frame :pr2 "base_footprint"))
  (<- (robot-base-link :pr2 "base_link"))
  (<- (robot-torso-link-joint :pr2 "torso_lift_link" "torso_lift_joint")))

;;; Keyed by :PR2, so these values apply only while the PR2 is the current robot (or no
;;; robot is current) and never shadow another description loaded in the same image.
;;; The PR2 samples one base orientation per position, so no sample step is given.
(def-fact-group pr2-costmap-metadata (costmap:robot-costmap-metadata)
  (<- (costmap:robot-costmap-metadata :pr2 (costmap:costmap-size 12 12)))
  (<- (costmap:robot-costmap-metadata :pr2 (costmap:costmap-origin -6 -6)))
  (<- (costmap:robot-costmap-metadata :pr2 (costmap:costmap-resolution 0.04)))

  (<- (costmap:robot-costmap-metadata :pr2 (costmap:costmap-padding 0.3)))
  (<- (costmap:robot-costmap-metadata :pr2 (costmap:costmap-manipulation-padding 0.4)))
  (<- (costmap:robot-costmap-metadata :pr2 (costmap:costmap-in-reach-distance 1.05)))
  (<- (costmap:robot-costmap-metadata :pr2 (costmap:costmap-reach-minimal-distance 0.2)))
  (<- (costmap:robot-costmap-metadata :pr2 (costmap:visibility-costmap-size 2)))
  (<- (costmap:robot-costmap-metadata :pr2 (costmap:orientation-samples 1))))
