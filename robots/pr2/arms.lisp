;;;; PR2: arms, wrists, grippers and named arm configurations.

(in-package :cram-pr2-description)

(defparameter *tcp-in-ee-pose*
  (cl-transforms:make-pose (cl-transforms:make-3d-vector 0.18 0 0)
                           (cl-transforms:make-identity-rotation))
  "The gripper tool frame in the wrist roll (end-effector) link frame: 0.18 m along x.")

(defparameter *standard-to-pr2-gripper-transform*
  (cl-transforms-stamped:make-identity-transform)
  "The PR2 gripper frame is the standard gripper frame (x forward between the fingers, z
up), so the transform is the identity.")

(defparameter *left-parking-joint-states*
  '(("l_shoulder_pan_joint" 1.9652919379395388d0)
    ("l_shoulder_lift_joint" -0.26499816732737785d0)
    ("l_upper_arm_roll_joint" 1.3837617139225473d0)
    ("l_elbow_flex_joint" -2.1224566064321584d0)
    ("l_forearm_roll_joint" 16.99646118944817d0)
    ("l_wrist_flex_joint" -0.07350789589924167d0)
    ("l_wrist_roll_joint" 0.0d0))
  "The left arm folded beside the body, out of the camera's view (:PARK, also :CARRY).")

(defparameter *right-parking-joint-states*
  '(("r_shoulder_pan_joint" -1.712587449591307d0)
    ("r_shoulder_lift_joint" -0.2567290370386635d0)
    ("r_upper_arm_roll_joint" -1.4633501125737374d0)
    ("r_elbow_flex_joint" -2.1221670650093913d0)
    ("r_forearm_roll_joint" 1.7663253481913623d0)
    ("r_wrist_flex_joint" -0.07942669250968948d0)
    ("r_wrist_roll_joint" 0.05106258161229582d0))
  "The right arm folded beside the body, out of the camera's view (:PARK, also :CARRY).")

(defparameter *left-carry-top-joint-states*
  '(("l_shoulder_pan_joint" 1.0252138d0)
    ("l_shoulder_lift_joint" -0.0696685d0)
    ("l_upper_arm_roll_joint" 1.1765833d0)
    ("l_elbow_flex_joint" -1.9323727d0)
    ("l_forearm_roll_joint" 1.3824994d0)
    ("l_wrist_flex_joint" -1.8416234d0)
    ("l_wrist_roll_joint" 2.9073737d0))
  "The left arm in front of the body, its gripper pointing down (:CARRY-TOP): for carrying a
bowl, or a cup or cereal box grasped from the top.")

(defparameter *right-carry-top-joint-states*
  '(("r_shoulder_pan_joint" -1.1838090d0)
    ("r_shoulder_lift_joint" -0.3068092d0)
    ("r_upper_arm_roll_joint" -1.6439096d0)
    ("r_elbow_flex_joint" -2.0632454d0)
    ("r_forearm_roll_joint" -1.3016362d0)
    ("r_wrist_flex_joint" -1.2849451d0)
    ("r_wrist_roll_joint" -1.9747830d0))
  "The right arm in front of the body, its gripper pointing down (:CARRY-TOP).")

(defun name-starts-with (prefix name)
  "True when NAME is a string that begins with PREFIX."
  (and (stringp name)
       (>= (length name) (length prefix))
       (string= prefix name :end2 (length prefix))))

(def-fact-group pr2-arm-facts (arm arm-joints arm-links end-effector-link robot-tool-frame
                               gripper-joint gripper-link gripper-meter-to-joint-multiplier
                               standard-to-particular-gripper-transform tcp-in-ee-pose
                               hand-links hand-finger-link robot-joint-states)
  (<- (arm :pr2 :left))
  (<- (arm :pr2 :right))

  (<- (arm-joints :pr2 :left ("l_shoulder_pan_joint" "l_shoulder_lift_joint"
                              "l_upper_arm_roll_joint" "l_elbow_flex_joint"
                              "l_forearm_roll_joint" "l_wrist_flex_joint"
                              "l_wrist_roll_joint")))
  (<- (arm-joints :pr2 :right ("r_shoulder_pan_joint" "r_shoulder_lift_joint"
                               "r_upper_arm_roll_joint" "r_elbow_flex_joint"
                               "r_forearm_roll_joint" "r_wrist_flex_joint"
                               "r_wrist_roll_joint")))

  (<- (arm-links :pr2 :left ("l_shoulder_pan_link" "l_shoulder_lift_link"
                             "l_upper_arm_roll_link" "l_upper_arm_link" "l_elbow_flex_link"
                             "l_forearm_roll_link" "l_forearm_link" "l_wrist_flex_link"
                             "l_wrist_roll_link")))
  (<- (arm-links :pr2 :right ("r_shoulder_pan_link" "r_shoulder_lift_link"
                              "r_upper_arm_roll_link" "r_upper_arm_link" "r_elbow_flex_link"
                              "r_forearm_roll_link" "r_forearm_link" "r_wrist_flex_link"
                              "r_wrist_roll_link")))

  (<- (end-effector-link :pr2 :left "l_wrist_roll_link"))
  (<- (end-effector-link :pr2 :right "r_wrist_roll_link"))

  (<- (robot-tool-frame :pr2 :left "l_gripper_tool_frame"))
  (<- (robot-tool-frame :pr2 :right "r_gripper_tool_frame"))

  ;; The gripper is commanded through its two revolute finger joints (0 closed to 0.548
  ;; open; the right finger mimics the left one).  The prismatic *_gripper_joint measures
  ;; the opening between the finger tips and is not commanded.
  (<- (gripper-joint :pr2 :left "l_gripper_l_finger_joint"))
  (<- (gripper-joint :pr2 :left "l_gripper_r_finger_joint"))
  (<- (gripper-joint :pr2 :right "r_gripper_l_finger_joint"))
  (<- (gripper-joint :pr2 :right "r_gripper_r_finger_joint"))

  (<- (gripper-link :pr2 :left ?link)
    (bound ?link)
    (lisp-pred name-starts-with "l_gripper" ?link))
  (<- (gripper-link :pr2 :right ?link)
    (bound ?link)
    (lisp-pred name-starts-with "r_gripper" ?link))

  (<- (gripper-meter-to-joint-multiplier :pr2 5.0))

  (<- (standard-to-particular-gripper-transform :pr2 ?transform)
    (symbol-value *standard-to-pr2-gripper-transform* ?transform))
  (<- (tcp-in-ee-pose :pr2 ?pose)
    (symbol-value *tcp-in-ee-pose* ?pose))

  (<- (hand-links :pr2 :left ("l_gripper_palm_link"
                              "l_gripper_l_finger_link" "l_gripper_l_finger_tip_link"
                              "l_gripper_r_finger_link" "l_gripper_r_finger_tip_link")))
  (<- (hand-links :pr2 :right ("r_gripper_palm_link"
                               "r_gripper_l_finger_link" "r_gripper_l_finger_tip_link"
                               "r_gripper_r_finger_link" "r_gripper_r_finger_tip_link")))

  (<- (hand-finger-link :pr2 :left ?link)
    (member ?link ("l_gripper_l_finger_link" "l_gripper_l_finger_tip_link"
                   "l_gripper_r_finger_link" "l_gripper_r_finger_tip_link")))
  (<- (hand-finger-link :pr2 :right ?link)
    (member ?link ("r_gripper_l_finger_link" "r_gripper_l_finger_tip_link"
                   "r_gripper_r_finger_link" "r_gripper_r_finger_tip_link")))

  (<- (robot-joint-states :pr2 :arm :left :park ?joint-states)
    (symbol-value *left-parking-joint-states* ?joint-states))
  (<- (robot-joint-states :pr2 :arm :right :park ?joint-states)
    (symbol-value *right-parking-joint-states* ?joint-states))
  (<- (robot-joint-states :pr2 :arm :left :carry ?joint-states)
    (symbol-value *left-parking-joint-states* ?joint-states))
  (<- (robot-joint-states :pr2 :arm :right :carry ?joint-states)
    (symbol-value *right-parking-joint-states* ?joint-states))
  (<- (robot-joint-states :pr2 :arm :left :carry-top ?joint-states)
    (symbol-value *left-carry-top-joint-states* ?joint-states))
  (<- (robot-joint-states :pr2 :arm :right :carry-top ?joint-states)
    (symbol-value *right-carry-top-joint-states* ?joint-states)))
