;;;; PR2: the pan-tilt head and its cameras.

(in-package :cram-pr2-description)

(def-fact-group pr2-neck-facts (robot-neck-links robot-neck-joints robot-neck-base-link
                                robot-neck-pan-joint-forward-facing-axis-sign
                                robot-neck-tilt-joint-forward-facing-axis-sign
                                camera-frame camera-minimal-height camera-maximal-height
                                camera-horizontal-angle camera-vertical-angle)
  (<- (robot-neck-links :pr2 "head_pan_link" "head_tilt_link"))
  (<- (robot-neck-joints :pr2 "head_pan_joint" "head_tilt_joint"))
  (<- (robot-neck-base-link :pr2 "torso_lift_link"))

  ;; Looking straight ahead is +x of the pan link; the tilt joint (axis +y) lowers the
  ;; gaze for positive angles, so the tilt computation uses x with the sign -1.
  (<- (robot-neck-pan-joint-forward-facing-axis-sign :pr2 cl-transforms:x 1))
  (<- (robot-neck-tilt-joint-forward-facing-axis-sign :pr2 cl-transforms:x -1))

  ;; The Kinect is the camera for visibility reasoning; the narrow stereo pair is second.
  (<- (camera-frame :pr2 "head_mount_kinect_rgb_optical_frame"))
  (<- (camera-frame :pr2 "narrow_stereo_optical_frame"))

  (<- (camera-minimal-height :pr2 1.27))
  (<- (camera-maximal-height :pr2 1.60))
  (<- (camera-horizontal-angle :pr2 0.995))
  (<- (camera-vertical-angle :pr2 0.75)))

;;; Looking straight ahead: pan and tilt at 0 (inside both joints' limits).
(def-fact-group pr2-neck-states (robot-joint-states)
  (<- (robot-joint-states :pr2 :neck ?there-is-only-one-neck :forward
                          (("head_pan_joint" 0.0d0) ("head_tilt_joint" 0.0d0)))))
