;;;; The interface predicates of robot descriptions.  Each one is declared here with a
;;;; clause that fails, so that a query about a robot without the fact is a plain "no";
;;;; robot descriptions add their clauses in their own fact groups (listing the predicate
;;;; among their extendable functors).  Every predicate takes the robot name first.

(in-package :cram-robot-interfaces)

(def-fact-group robot-metadata (robot robot-base-frame robot-base-link robot-odom-frame
                                robot-torso-link-joint robot-joint-states)
  ;; When a current robot is set, it is the only answer; else the described robot loaded in the
  ;; belief state (LOADED-ROBOT-NAME); else every robot a loaded description declares.
  (<- (robot ?robot-name)
    (symbol-value *robot-name* ?current)
    (lisp-pred identity ?current)
    (cut)
    (== ?robot-name ?current))
  (<- (robot ?robot-name)
    (lisp-fun loaded-robot-name ?loaded)
    (lisp-pred identity ?loaded)
    (cut)
    (== ?robot-name ?loaded))
  (<- (robot-base-frame ?robot-name ?frame) (fail))
  (<- (robot-base-link ?robot-name ?link) (fail))
  (<- (robot-odom-frame ?robot-name ?frame) (fail))
  (<- (robot-torso-link-joint ?robot-name ?link ?joint) (fail))
  (<- (robot-joint-states ?robot-name ?joints-type ?joints-id ?state-name ?joint-states)
    (fail)))

(def-fact-group arm-facts (arm arm-joints arm-links end-effector-link robot-tool-frame
                           gripper-joint gripper-link gripper-meter-to-joint-multiplier
                           standard-to-particular-gripper-transform tcp-in-ee-pose
                           hand-links hand-link hand-finger-link)
  (<- (arm ?robot-name ?arm) (fail))
  (<- (arm-joints ?robot-name ?arm ?joints) (fail))
  (<- (arm-links ?robot-name ?arm ?links) (fail))
  (<- (end-effector-link ?robot-name ?arm ?link) (fail))
  (<- (robot-tool-frame ?robot-name ?arm ?frame) (fail))
  (<- (gripper-joint ?robot-name ?arm ?joint) (fail))
  (<- (gripper-link ?robot-name ?arm ?link) (fail))
  (<- (gripper-meter-to-joint-multiplier ?robot-name ?multiplier) (fail))
  (<- (standard-to-particular-gripper-transform ?robot-name ?transform) (fail))
  (<- (tcp-in-ee-pose ?robot-name ?pose) (fail))
  (<- (hand-links ?robot-name ?arm ?links) (fail))
  (<- (hand-link ?robot-name ?arm ?link)
    (hand-links ?robot-name ?arm ?links)
    (member ?link ?links))
  (<- (hand-finger-link ?robot-name ?arm ?link) (fail)))

(def-fact-group neck-and-camera-facts (robot-neck-links robot-neck-joints robot-neck-base-link
                                       robot-neck-pan-joint-forward-facing-axis-sign
                                       robot-neck-tilt-joint-forward-facing-axis-sign
                                       camera-frame camera-minimal-height camera-maximal-height
                                       camera-horizontal-angle camera-vertical-angle
                                       camera-in-neck-ee-pose)
  (<- (robot-neck-links ?robot-name . ?links) (fail))
  (<- (robot-neck-joints ?robot-name . ?joints) (fail))
  (<- (robot-neck-base-link ?robot-name ?link) (fail))
  (<- (robot-neck-pan-joint-forward-facing-axis-sign ?robot-name ?axis ?sign) (fail))
  (<- (robot-neck-tilt-joint-forward-facing-axis-sign ?robot-name ?axis ?sign) (fail))
  (<- (camera-frame ?robot-name ?frame) (fail))
  (<- (camera-minimal-height ?robot-name ?height) (fail))
  (<- (camera-maximal-height ?robot-name ?height) (fail))
  (<- (camera-horizontal-angle ?robot-name ?angle) (fail))
  (<- (camera-vertical-angle ?robot-name ?angle) (fail))
  (<- (camera-in-neck-ee-pose ?robot-name ?pose) (fail)))

(define-predicate-documentation
  (robot "(robot ?robot-name): the robot. With *ROBOT-NAME* set, exactly that name;
otherwise every robot a loaded description declares.")
  (robot-base-frame "(robot-base-frame ?robot-name ?frame): the TF frame of the mobile base,
e.g. \"base_footprint\".")
  (robot-base-link "(robot-base-link ?robot-name ?link): the main link of the base.")
  (robot-odom-frame "(robot-odom-frame ?robot-name ?frame): the odometry frame.")
  (robot-torso-link-joint "(robot-torso-link-joint ?robot-name ?link ?joint): the torso link
and the joint that moves it.")
  (robot-joint-states "(robot-joint-states ?robot-name ?joints-type ?joints-id ?state-name
?joint-states): a named configuration, e.g. ?joints-type :arm, ?joints-id :left, ?state-name
:park, as a list of (joint-name value) pairs.")
  (arm "(arm ?robot-name ?arm): ?arm (:left, :right) is an arm of the robot.")
  (arm-joints "(arm-joints ?robot-name ?arm ?joints): the arm's joint names from the base
to the wrist, in kinematic order.")
  (arm-links "(arm-links ?robot-name ?arm ?links): the arm's link names in kinematic order.")
  (end-effector-link "(end-effector-link ?robot-name ?arm ?link): the last link of the arm
chain; grasped objects are attached to it.")
  (robot-tool-frame "(robot-tool-frame ?robot-name ?arm ?frame): the tool centre point frame.")
  (gripper-joint "(gripper-joint ?robot-name ?arm ?joint): each joint commanded when the
gripper opens or closes (one solution per joint).")
  (gripper-link "(gripper-link ?robot-name ?arm ?link): ?link belongs to the gripper;
descriptions may require ?link to be bound.")
  (gripper-meter-to-joint-multiplier "(gripper-meter-to-joint-multiplier ?robot-name ?m):
a gripper opening of d metres sets each gripper joint to d × ?m.")
  (standard-to-particular-gripper-transform "(standard-to-particular-gripper-transform
?robot-name ?transform): the transform from the standard gripper frame (x forward) to this
robot's tool frame.")
  (tcp-in-ee-pose "(tcp-in-ee-pose ?robot-name ?pose): the tool frame expressed in the
end-effector link frame.")
  (hand-links "(hand-links ?robot-name ?arm ?links): the links of the hand (palm and
fingers), used for contact checks.")
  (hand-link "(hand-link ?robot-name ?arm ?link): ?link is a member of HAND-LINKS.")
  (hand-finger-link "(hand-finger-link ?robot-name ?arm ?link): ?link is a finger link.")
  (robot-neck-links "(robot-neck-links ?robot-name . ?links): the neck links from base to
head, e.g. pan link then tilt link.")
  (robot-neck-joints "(robot-neck-joints ?robot-name . ?joints): the neck joints from base to
head, e.g. pan joint then tilt joint.")
  (robot-neck-base-link "(robot-neck-base-link ?robot-name ?link): the link the neck chain is
mounted on.")
  (robot-neck-pan-joint-forward-facing-axis-sign "(robot-neck-pan-joint-forward-facing-axis-sign
?robot-name ?axis ?sign): the axis accessor (cl-transforms:x, y or z) and sign (1 or -1) of
the pan link axis that points forward.")
  (robot-neck-tilt-joint-forward-facing-axis-sign "(robot-neck-tilt-joint-forward-facing-axis-sign
?robot-name ?axis ?sign): the axis accessor and sign of the tilt link axis that points forward.")
  (camera-frame "(camera-frame ?robot-name ?frame): a camera's optical frame; the first
solution is the camera used for visibility reasoning.")
  (camera-minimal-height "(camera-minimal-height ?robot-name ?height): the lowest camera
height above the floor, in metres.")
  (camera-maximal-height "(camera-maximal-height ?robot-name ?height): the highest camera
height above the floor, in metres.")
  (camera-horizontal-angle "(camera-horizontal-angle ?robot-name ?angle): the horizontal
field of view in radians.")
  (camera-vertical-angle "(camera-vertical-angle ?robot-name ?angle): the vertical field of
view in radians.")
  (camera-in-neck-ee-pose "(camera-in-neck-ee-pose ?robot-name ?pose): the camera pose in the
frame of the last neck link, for necks with more than two joints."))
