;;;; Tests of the robot interfaces (ROB-INT), the PR2 and Pepper descriptions, and the
;;;; costmap metadata predicates.

(defpackage :cram-robots-tests
  (:use :cl :fiveam))

(in-package :cram-robots-tests)

(def-suite robots :in cram-plans-tests:all
  :description "Robot-description facts of the PR2 and Pepper, the current robot, costmap metadata.")
(in-suite robots)

(defun query-values (variable query)
  "Every value VARIABLE takes in the solutions of QUERY, in order."
  (mapcar (lambda (bindings) (cut:var-value variable bindings))
          (cut:force-ll (prolog:prolog query))))

(defun query-value (variable query)
  "The value of VARIABLE in the first solution of QUERY."
  (first (query-values variable query)))

(defun value-of (name bindings)
  "The value of the query variable ?NAME (a string designator) in BINDINGS."
  (cut:var-value (intern (concatenate 'string "?" (string-upcase (string name)))
                         :cram-robots-tests)
                 bindings))

(defun holds (query)
  "True when QUERY has a solution."
  (not (null (prolog:prolog query))))

(defmacro with-robot ((name) &body body)
  "Run BODY with ROB-INT:*ROBOT-NAME* bound to NAME and no robot taken from a belief state (a
suite run before may have left one loaded)."
  `(let ((rob-int:*robot-name* ,name)
         (rob-int::*loaded-robot-name-function* nil))
     ,@body))

(defparameter *pepper* 'pepper-descr:pepper)

;;; The interface

(test interface-predicates-fail-for-unknown-robots
  (let ((joints (query-values '?j '(rob-int:arm-joints :no-such-robot :left ?j)))
        (frame (query-values '?f '(rob-int:camera-frame :no-such-robot ?f)))
        (neck (query-values '?l '(rob-int:robot-neck-links :no-such-robot . ?l)))
        (states (query-values '?s '(rob-int:robot-joint-states :no-such-robot :arm :left :park ?s))))
    (is (null joints))
    (is (null frame))
    (is (null neck))
    (is (null states))))

(test robot-follows-the-current-robot
  (let ((all (with-robot (nil) (query-values '?r '(rob-int:robot ?r))))
        (as-pr2 (with-robot (:pr2) (query-values '?r '(rob-int:robot ?r))))
        (as-pepper (with-robot (*pepper*) (query-values '?r '(rob-int:robot ?r))))
        (pr2-is-robot-when-pepper (with-robot (*pepper*) (holds '(rob-int:robot :pr2)))))
    (is (member :pr2 all))
    (is (member *pepper* all))
    (is (equal '(:pr2) as-pr2))
    (is (equal (list *pepper*) as-pepper))
    (is (not pr2-is-robot-when-pepper))))

(test described-robot-names-ignores-the-current-robot
  (let ((names (with-robot (:pr2) (rob-int:described-robot-names))))
    (is (member :pr2 names))
    (is (member *pepper* names))
    (is (= (length names) (length (remove-duplicates names))))))

(test set-robot-name-maps-urdf-names-to-description-symbols
  (with-robot (nil)
    (is (eq :pr2 (rob-int:set-robot-name "pr2")))
    (is (eq :pr2 rob-int:*robot-name*))
    (is (eq :pr2 (rob-int:current-robot-name)))
    (is (eq *pepper* (rob-int:set-robot-name "pepper")))
    (is (eq *pepper* (rob-int:current-robot-name)))
    (is (eq :pr2 (rob-int:set-robot-name "PR2")))
    (is (eq *pepper* (rob-int:set-robot-name :pepper)))
    (is (eq :pr2 (rob-int:set-robot-name :pr2)))
    (is (eq *pepper* (rob-int:set-robot-name *pepper*)))))

(test set-robot-name-rejects-unknown-and-malformed-names
  (with-robot (:pr2)
    (signals rob-int:robot-interface-error (rob-int:set-robot-name "tiago_dual"))
    (is (eq :pr2 rob-int:*robot-name*) "a rejected name leaves the current robot unchanged")
    (signals rob-int:robot-interface-error (rob-int:set-robot-name 42))
    (signals rob-int:robot-interface-error (rob-int:set-robot-name ""))
    (signals rob-int:robot-interface-error (rob-int:set-robot-name nil))
    (is (eq :tiago-dual (rob-int:set-robot-name "tiago_dual" :require-description nil)))
    (is (eq :tiago-dual (rob-int:current-robot-name)))))

(test unknown-robot-error-names-the-value-and-the-choices
  (let ((message (handler-case (progn (rob-int:set-robot-name "tiago_dual") "no error")
                   (rob-int:robot-interface-error (e) (princ-to-string e)))))
    (is (search "tiago_dual" message))
    (is (search ":PR2" message))
    (is (search "PEPPER" message))))

(test urdf-name-convention
  (is (eq :pr2 (rob-int:urdf-name->robot-name "pr2")))
  (is (eq :iai-donbot (rob-int:urdf-name->robot-name "iai_donbot")))
  (is (eq :boxy-description (rob-int:urdf-name->robot-name "boxy_description")))
  (signals rob-int:robot-interface-error (rob-int:urdf-name->robot-name :pr2))
  (signals rob-int:robot-interface-error (rob-int:urdf-name->robot-name "  ")))

(test current-robot-name-without-a-robot-is-an-error
  (with-robot (nil)
    (let ((message (handler-case (progn (rob-int:current-robot-name) "no error")
                     (rob-int:robot-interface-error (e) (princ-to-string e)))))
      (is (search "set-robot-name" message))
      (is (search "*ROBOT-NAME*" message))
      (is (search ":PR2" message)))))

;;; PR2

(defparameter *pr2-left-arm-joints*
  '("l_shoulder_pan_joint" "l_shoulder_lift_joint" "l_upper_arm_roll_joint"
    "l_elbow_flex_joint" "l_forearm_roll_joint" "l_wrist_flex_joint" "l_wrist_roll_joint"))

(defparameter *pr2-right-arm-joints*
  '("r_shoulder_pan_joint" "r_shoulder_lift_joint" "r_upper_arm_roll_joint"
    "r_elbow_flex_joint" "r_forearm_roll_joint" "r_wrist_flex_joint" "r_wrist_roll_joint"))

(test pr2-frames-and-torso
  (let ((odom (query-values '?f '(rob-int:robot-odom-frame :pr2 ?f)))
        (base (query-values '?f '(rob-int:robot-base-frame :pr2 ?f)))
        (base-link (query-values '?l '(rob-int:robot-base-link :pr2 ?l)))
        (torso (first (cut:force-ll
                       (prolog:prolog '(rob-int:robot-torso-link-joint :pr2 ?link ?joint))))))
    (is (equal '("odom_combined") odom))
    (is (equal '("base_footprint") base))
    (is (equal '("base_link") base-link))
    (is (equal "torso_lift_link" (value-of :link torso)))
    (is (equal "torso_lift_joint" (value-of :joint torso)))))

(test pr2-arms-joints-and-links
  (let ((arms (query-values '?a '(rob-int:arm :pr2 ?a)))
        (left (query-values '?j '(rob-int:arm-joints :pr2 :left ?j)))
        (right (query-values '?j '(rob-int:arm-joints :pr2 :right ?j)))
        (left-links (query-value '?l '(rob-int:arm-links :pr2 :left ?l)))
        (right-links (query-value '?l '(rob-int:arm-links :pr2 :right ?l))))
    (is (equal '(:left :right) arms))
    (is (equal (list *pr2-left-arm-joints*) left))
    (is (equal (list *pr2-right-arm-joints*) right))
    (is (equal *pr2-left-arm-joints* (rob-int:get-arm-joints :pr2 :left)))
    (is (equal left-links (rob-int:get-arm-links :pr2 :left)))
    (is (= 9 (length left-links)))
    (is (equal "l_shoulder_pan_link" (first left-links)))
    (is (equal "r_wrist_roll_link" (car (last right-links))))
    (is (every (lambda (l r) (string= (subseq l 1) (subseq r 1))) left-links right-links))
    (signals rob-int:robot-interface-error (rob-int:get-arm-joints :pr2 :middle))
    (signals rob-int:robot-interface-error (rob-int:get-arm-links :no-such-robot :left))))

(test pr2-end-effector-tool-frame-and-tcp
  (let ((ee-left (query-values '?l '(rob-int:end-effector-link :pr2 :left ?l)))
        (ee-right (query-values '?l '(rob-int:end-effector-link :pr2 :right ?l)))
        (tool-left (query-values '?f '(rob-int:robot-tool-frame :pr2 :left ?f)))
        (tool-right (query-values '?f '(rob-int:robot-tool-frame :pr2 :right ?f)))
        (tcp (query-value '?p '(rob-int:tcp-in-ee-pose :pr2 ?p)))
        (standard (query-value '?t '(rob-int:standard-to-particular-gripper-transform :pr2 ?t))))
    (is (equal '("l_wrist_roll_link") ee-left))
    (is (equal '("r_wrist_roll_link") ee-right))
    (is (equal '("l_gripper_tool_frame") tool-left))
    (is (equal '("r_gripper_tool_frame") tool-right))
    (is (typep tcp 'cl-transforms:pose))
    (let ((origin (cl-transforms:origin tcp))
          (rotation (cl-transforms:orientation tcp)))
      (is (< (abs (- 0.18d0 (cl-transforms:x origin))) 1d-12))
      (is (zerop (cl-transforms:y origin)))
      (is (zerop (cl-transforms:z origin)))
      (is (= 1 (cl-transforms:w rotation))))
    (is (typep standard 'cl-transforms:transform))
    (is (zerop (cl-transforms:v-norm (cl-transforms:translation standard))))
    (is (= 1 (cl-transforms:w (cl-transforms:rotation standard))))))

(test pr2-grippers
  (let ((left (query-values '?j '(rob-int:gripper-joint :pr2 :left ?j)))
        (right (query-values '?j '(rob-int:gripper-joint :pr2 :right ?j)))
        (multiplier (query-values '?m '(rob-int:gripper-meter-to-joint-multiplier :pr2 ?m)))
        (palm-left (holds '(rob-int:gripper-link :pr2 :left "l_gripper_palm_link")))
        (tip-left (holds '(rob-int:gripper-link :pr2 :left "l_gripper_r_finger_tip_link")))
        (palm-cross (holds '(rob-int:gripper-link :pr2 :right "l_gripper_palm_link")))
        (wrist (holds '(rob-int:gripper-link :pr2 :left "l_wrist_roll_link")))
        (hand (query-value '?l '(rob-int:hand-links :pr2 :right ?l)))
        (hand-link (holds '(rob-int:hand-link :pr2 :left "l_gripper_l_finger_tip_link")))
        (fingers (query-values '?l '(rob-int:hand-finger-link :pr2 :left ?l))))
    (is (equal '("l_gripper_l_finger_joint" "l_gripper_r_finger_joint") left))
    (is (equal '("r_gripper_l_finger_joint" "r_gripper_r_finger_joint") right))
    (is (equal '(5.0) multiplier))
    (is-true palm-left)
    (is-true tip-left)
    (is-false palm-cross)
    (is-false wrist)
    (is (equal "r_gripper_palm_link" (first hand)))
    (is (= 5 (length hand)))
    (is-true hand-link)
    (is (= 4 (length fingers)))
    (is (not (member "l_gripper_palm_link" fingers :test #'string=)))))

(test pr2-named-arm-configurations
  (let ((left-park (query-value '?s '(rob-int:robot-joint-states :pr2 :arm :left :park ?s)))
        (left-carry (query-value '?s '(rob-int:robot-joint-states :pr2 :arm :left :carry ?s)))
        (right-park (query-value '?s '(rob-int:robot-joint-states :pr2 :arm :right :park ?s)))
        (right-carry (query-value '?s '(rob-int:robot-joint-states :pr2 :arm :right :carry ?s))))
    (is (equal *pr2-left-arm-joints* (mapcar #'first left-park)))
    (is (equal *pr2-right-arm-joints* (mapcar #'first right-park)))
    (is (equal left-park left-carry))
    (is (equal right-park right-carry))
    (is (= 1.9652919379395388d0 (second (first left-park))))
    (is (= -1.712587449591307d0 (second (first right-park))))
    (is (= 0.05106258161229582d0 (second (car (last right-park)))))
    (is (equal left-park (rob-int:get-robot-joint-states :pr2 :arm :left :park)))
    (signals rob-int:robot-interface-error
      (rob-int:get-robot-joint-states :pr2 :arm :left :no-such-configuration))))

(test pr2-neck-and-cameras
  (let ((links (query-values '?l '(rob-int:robot-neck-links :pr2 . ?l)))
        (joints (query-values '?j '(rob-int:robot-neck-joints :pr2 . ?j)))
        (base (query-values '?l '(rob-int:robot-neck-base-link :pr2 ?l)))
        (pan (first (cut:force-ll (prolog:prolog
                                   '(rob-int:robot-neck-pan-joint-forward-facing-axis-sign
                                     :pr2 ?axis ?sign)))))
        (tilt (first (cut:force-ll (prolog:prolog
                                    '(rob-int:robot-neck-tilt-joint-forward-facing-axis-sign
                                      :pr2 ?axis ?sign)))))
        (frames (query-values '?f '(rob-int:camera-frame :pr2 ?f)))
        (low (query-value '?h '(rob-int:camera-minimal-height :pr2 ?h)))
        (high (query-value '?h '(rob-int:camera-maximal-height :pr2 ?h)))
        (horizontal (query-value '?a '(rob-int:camera-horizontal-angle :pr2 ?a)))
        (vertical (query-value '?a '(rob-int:camera-vertical-angle :pr2 ?a))))
    (is (equal '(("head_pan_link" "head_tilt_link")) links))
    (is (equal '(("head_pan_joint" "head_tilt_joint")) joints))
    (is (equal '("torso_lift_link") base))
    (is (eq 'cl-transforms:x (value-of :axis pan)))
    (is (= 1 (value-of :sign pan)))
    (is (eq 'cl-transforms:x (value-of :axis tilt)))
    (is (= -1 (value-of :sign tilt)))
    (is (equal "head_mount_kinect_rgb_optical_frame" (first frames)))
    (is (member "narrow_stereo_optical_frame" frames :test #'string=))
    (is (= 1.27 low))
    (is (= 1.60 high))
    (is (= 0.995 horizontal))
    (is (= 0.75 vertical))))
