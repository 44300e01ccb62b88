;;;; Package CRAM-BULLET-WORLD-TUTORIAL (BTW-TUT): the Bullet world tutorials' setup — the
;;;; kitchen, the PR2 and the tutorial meshes in a fresh belief state, with or without ROS.

(defpackage :cram-bullet-world-tutorial
  (:nicknames :btw-tut)
  (:use :cl :cram-prolog)
  (:export #:init-projection #:add-objects-to-mesh-list #:get-kitchen-urdf #:get-robot-urdf
           #:move-kitchen-joint #:spawn-bottle #:move-bottle #:find-object #:pick-up-object
           #:get-preferred-arm-for-direction #:*base-pose-near-table* #:*base-pose-near-counter*
           #:*final-object-destination* #:*downward-look-coordinate*
           #:*left-downward-look-coordinate* #:*right-downward-look-coordinate*
           #:*bottle-pose-in-view* #:*bottle-pose-out-of-view* #:*bottle-pose-hard-to-grasp*
           #:spawn-two-bottles #:test-switch-two-bottles #:navigate-to #:look-at
           #:get-perceived-bottle-desig #:pick-up #:place-down #:move-to-reach
           #:move-arm-out-of-sight #:*pose-bottle-1* #:*pose-bottle-2* #:*pose-meal-table*
           #:*pose-counter* #:*robot-parameter* #:*kitchen-parameter*))

(in-package :cram-bullet-world-tutorial)

(defparameter *robot-parameter* nil
  "The ROS parameter holding the robot URDF; NIL: the one ROB-INT:*ROBOT-DESCRIPTION-PARAMETER*
names (\"robot_description\").")
(defparameter *kitchen-parameter* "kitchen_description"
  "The ROS parameter holding the kitchen URDF.")

(defvar *robot-urdf* nil "The parsed robot URDF, read once.")
(defvar *kitchen-urdf* nil "The parsed kitchen URDF, read once.")

(defun read-urdf (parameter fallback-file)
  "The parsed URDF from the ROS parameter PARAMETER while a node runs and it is set, else from
FALLBACK-FILE (relative to the repository root)."
  (cl-urdf:parse-urdf (roslisp-utilities:robot-description-string
                       :parameter parameter :fallback-file fallback-file)))

(defun get-robot-urdf ()
  "The PR2 URDF: from the parameter *ROBOT-PARAMETER* under ROS, else robots/pr2/pr2.urdf."
  (or *robot-urdf*
      (setf *robot-urdf* (read-urdf (or *robot-parameter* rob-int:*robot-description-parameter*)
                                    "robots/pr2/pr2.urdf"))))

(defun get-kitchen-urdf ()
  "The kitchen URDF: from *KITCHEN-PARAMETER* under ROS, else resources/iai_kitchen.urdf."
  (or *kitchen-urdf*
      (setf *kitchen-urdf* (read-urdf *kitchen-parameter* "resources/iai_kitchen.urdf"))))

(defun add-objects-to-mesh-list (&optional (ros-package "cram_plans_resources"))
  "Make the tutorial meshes (:bottle, :cup, :fork-plastic ...) known as mesh keywords."
  (btr:add-objects-to-mesh-list ros-package :directory "meshes"))

(defun robot-park-joint-states (robot-name)
  (loop for arm in '(:left :right)
        append (ignore-errors (rob-int:get-robot-joint-states robot-name :arm arm :park))))

(defun fresh-world ()
  (let ((old btr:*current-bullet-world*))
    (setf btr:*current-bullet-world* (make-instance 'btr:bt-reasoning-world))
    (when (and old (not (eq old btr:*current-bullet-world*)))
      (ignore-errors (btr:destroy-world old)))
    btr:*current-bullet-world*))

(defun init-projection ()
  "Make a fresh belief state with the floor, the kitchen (:IAI-KITCHEN) and the PR2 at the
origin with parked arms and the torso halfway up; read the URDFs from ROS parameters when a
node runs, else from the project's files."
  (coe:clear-belief)
  (let* ((kitchen (get-kitchen-urdf))
         (robot (get-robot-urdf))
         (robot-name (rob-int:set-robot-name (cl-urdf:name robot)))
         (kitchen-name (rob-int:urdf-name->robot-name (cl-urdf:name kitchen))))
    (setf rob-int:*robot-urdf* robot
          rob-int:*environment-urdf* kitchen
          btr:*environment-name* kitchen-name
          cram-tf:*robot-base-frame* (or (rob-int::first-solution-value
                                          '?f `(rob-int:robot-base-frame ,robot-name ?f))
                                         "base_footprint"))
    (unless (assoc :bottle btr:*mesh-files*) (add-objects-to-mesh-list))
    (if (template-world-for kitchen robot)
        (install-copy-of-template)
        (build-world kitchen kitchen-name robot robot-name)))
  (setf cram-tf:*tf-default-timeout* 2.0
        prolog:*break-on-lisp-errors* t)
  btr:*current-bullet-world*)

(defvar *template* nil
  "(kitchen-urdf robot-urdf world): a copy of the belief state INIT-PROJECTION built last from
those parsed URDFs. INIT-PROJECTION gives a copy of it again while the URDFs are the same
objects: a copy costs a fifth of building the world.")

(defun template-world-for (kitchen robot)
  "The template world when it was built from the URDFs KITCHEN and ROBOT and still exists."
  (destructuring-bind (&optional k r world) *template*
    (and (eq k kitchen) (eq r robot) world
         (cram-native:world-alive-p (btr:world-handle world))
         world)))

(defun install-copy-of-template ()
  "Make a copy of the template world the current world (destroying the previous one)."
  (let ((old btr:*current-bullet-world*))
    (setf btr:*current-bullet-world* (btr:copy-world (third *template*)))
    (when (and old (not (eq old (third *template*))))
      (ignore-errors (btr:destroy-world old)))
    (btr:debug-window btr:*current-bullet-world*)))

(defun build-world (kitchen kitchen-name robot robot-name)
  "Build the belief state from the URDFs: floor, kitchen, robot with parked arms and the torso
halfway up; keep a copy of it as the template."
  (fresh-world)
  (let ((world btr:*current-bullet-world*))
    (btr:add-object world :static-plane :floor '((0 0 0) (0 0 0 1))
                    :normal '(0 0 1) :constant 0)
    (btr:add-object world :urdf kitchen-name '((0 0 0) (0 0 0 1)) :urdf kitchen
                    :collision-group :static-filter
                    :collision-mask '(:default-filter :character-filter))
    ;; :compound t: a robot URDF with meshes (robot_description under ROS) collides with one
    ;; convex hull per sub-mesh of each link mesh, as it always has here
    (let ((pr2 (btr:add-object world :urdf robot-name '((0 0 0) (0 0 0 1)) :urdf robot
                               :compound t)))
      (btr:set-robot-state-from-joints (robot-park-joint-states robot-name) pr2)
      (multiple-value-bind (torso-link torso-joint)
          (let ((b (car (prolog `(rob-int:robot-torso-link-joint ,robot-name ?l ?j)))))
            (values (cut:var-value '?l b) (cut:var-value '?j b)))
        (declare (ignore torso-link))
        (when (and (stringp torso-joint) (member torso-joint (btr:joint-names pr2) :test #'equal))
          (multiple-value-bind (lo hi) (btr:joint-limits pr2 torso-joint)
            (when (and lo hi)
              (btr:set-robot-state-from-joints `((,torso-joint ,(/ (+ lo hi) 2))) pr2))))))
    (let ((old (third *template*)))
      (setf *template* (list kitchen robot (btr:copy-world world)))
      (when old (ignore-errors (btr:destroy-world old))))
    (btr:debug-window world)))

(defun move-kitchen-joint (&key (joint-name "iai_fridge_door_joint") (joint-angle 0.2d0)
                             (kitchen-name btr:*environment-name*))
  "Set the kitchen joint JOINT-NAME to JOINT-ANGLE in the belief state."
  (btr:set-robot-state-from-joints
   `((,joint-name ,joint-angle))
   (or (btr:object btr:*current-bullet-world* kitchen-name)
       (error "MOVE-KITCHEN-JOINT: there is no kitchen object ~s in the world." kitchen-name))))

(roslisp-utilities:register-ros-init-function init-projection)
