;;;; Tests of the plans layer: object knowledge, groundings, move-bottle with its recoveries,
;;;; switching two bottles and the Pepper shopping assistant.

(defpackage :cram-plans-tests-plans
  (:use :cl :fiveam))

(in-package :cram-plans-tests-plans)

(def-suite plans :in cram-plans-tests:all :description "Plans, tutorials and demos.")
(in-suite plans)

(defun run-logged (thunk)
  "Call THUNK with the CPL log captured; returns its value (or the error) and the log text."
  (let* ((s (make-string-output-stream))
         (value (let ((cpl:*log-stream* s))
                  (handler-case (funcall thunk) (error (e) e)))))
    (values value (get-output-stream-string s))))

(defun bottle-distance ()
  (cl-transforms:v-dist (cl-transforms:origin (btr:pose (btr:object btr:*current-bullet-world*
                                                                     'btw-tut::bottle-1)))
                        (cl-transforms:origin btw-tut:*final-object-destination*)))

(defun move-bottle-logged (pose)
  "Run move-bottle to POSE in a fresh projection; check that it returned the object and that the
bottle arrived; return the log."
  (btw-tut:init-projection)
  (multiple-value-bind (value log) (run-logged (lambda () (btw-tut:move-bottle pose)))
    (is (typep value 'desig:object-designator) "move-bottle failed: ~a" value)
    (is (< (bottle-distance) 0.03))
    log))

(test bottle-grasps
  (is (equal '(:left-side :right-side :back :front) (man-int:object-type-grasps :bottle)))
  (is (null (member :top (man-int:object-type-grasps :bottle))))
  (is (member :top (man-int:object-type-grasps :cup)))
  (is (= 20 (man-int:get-object-type-gripping-effort :milk)))
  (is (= 0.05 (man-int:get-object-type-gripper-opening :fork-plastic)))
  (signals man-int:manipulation-knowledge-error (man-int:object-type-grasps :unicorn))
  (signals man-int:manipulation-knowledge-error
    (man-int:get-object-type-to-gripper-transform :bottle nil :right :top)))

(test bottle-trajectory
  (let* ((pose (cl-transforms:make-pose (cl-transforms:make-3d-vector 1 2 0.9)
                                        (cl-transforms:make-identity-rotation)))
         (traj (man-int:get-action-trajectory :picking-up :right :left-side :bottle pose))
         (grasp (first (man-int:get-traj-poses-by-label traj :grasping)))
         (reach (man-int:get-traj-poses-by-label traj :reaching))
         (lift (man-int:get-traj-poses-by-label traj :lifting)))
    (is (= 2 (length reach)))
    (is (< (abs (- 2.02 (cl-transforms:y (cl-transforms:origin grasp)))) 1d-6))
    (is (< (abs (- 0.905 (cl-transforms:z (cl-transforms:origin grasp)))) 1d-6))
    ;; the first pregrasp is 0.15 m back (+y for a left-side grasp) and 0.07 m up
    (is (< (abs (- 2.17 (cl-transforms:y (cl-transforms:origin (first reach))))) 1d-6))
    (is (< (abs (- 0.975 (cl-transforms:z (cl-transforms:origin (first reach))))) 1d-6))
    (is (< (abs (- 1.045 (cl-transforms:z (cl-transforms:origin (second lift))))) 1d-6))
    (signals man-int:manipulation-knowledge-error
      (man-int:get-traj-poses-by-label traj :putting))))

(test action-grounding-errors
  (btw-tut:init-projection)
  (let ((d (desig:an action (type picking-up) (arm :right))))
    (signals error (exe:perform d)))
  (let ((d (desig:an action (type moving-torso) (joint-angle :high))))
    (signals error (desig:reference d) (exe:perform d))))

(test move-bottle-in-view
  (let ((log (move-bottle-logged btw-tut:*bottle-pose-in-view*)))
    (dolist (line '("Opening gripper and reaching" "Grasping" "Gripping"
                    "Assert grasp into knowledge base" "Lifting" "Putting"
                    "Retract grasp in knowledge base" "Retracting"))
      (is (search line log) "log lacks ~s" line))
    (is (search "[(PICK-PLACE PICK-UP) INFO] " log))
    (is (null (search "Turning head." log)))))

(test move-bottle-out-of-view
  (let ((log (move-bottle-logged btw-tut:*bottle-pose-out-of-view*)))
    (is (search "Turning head." log))))

(test move-bottle-hard-to-grasp
  (let ((log (move-bottle-logged btw-tut:*bottle-pose-hard-to-grasp*)))
    ;; the first grasp fails and the next one, from the side facing the robot, is tried
    (is (search "Failed to grasp from LEFT-SIDE using RIGHT arm" log) "log: ~a" log)
    (is (search "[(TRYING-NEW-GRASP) INFO]" log))
    (is (search "Trying to grasp from RIGHT-SIDE using RIGHT arm" log))
    (is (null (search "Failed to grasp from RIGHT-SIDE" log)))))

(test switch-two-bottles
  (btw-tut:init-projection)
  (let ((value (run-logged #'btw-tut:test-switch-two-bottles)))
    (is (listp value) "switching failed: ~a" value)
    (flet ((at (name pose)
             (let ((p (cl-transforms:origin (btr:pose (btr:object btr:*current-bullet-world* name))))
                   (q (cl-transforms:origin pose)))
               (< (sqrt (+ (expt (- (cl-transforms:x p) (cl-transforms:x q)) 2)
                           (expt (- (cl-transforms:y p) (cl-transforms:y q)) 2)))
                  0.03))))
      (is (at 'btw-tut::bottle-1 btw-tut:*pose-bottle-2*))
      (is (at 'btw-tut::bottle-2 btw-tut:*pose-bottle-1*)))))

(defun run-interaction (input &key remove)
  (demo:init-projection)
  (demo:spawn-products-one)
  (dolist (name remove) (btr:remove-object btr:*current-bullet-world* name))
  (let* ((out (make-string-output-stream))
         (values (let ((*standard-input* (make-string-input-stream input))
                       (*standard-output* out)
                       (cpl:*log-stream* (make-broadcast-stream)))
                   (multiple-value-list (demo:interaction)))))
    (values values (get-output-stream-string out))))

(test pepper-cereal
  (multiple-value-bind (values text) (run-interaction "1 1")
    (is (eq 'demo::cereal (first values)))
    (is (second values))
    (is (search "There is your product!" text))
    (let ((human (cl-transforms:origin (btr:pose (btr:object btr:*current-bullet-world* :my-human)))))
      (is (> (cl-transforms:v-dist human (cl-transforms:make-3d-vector -1 0 1)) 0.5)))))

(test pepper-milk
  (multiple-value-bind (values text) (run-interaction "1 2")
    (is (eq 'demo::milk (first values)))
    (is (search "There is your product!" text))))

(test pepper-hi
  (multiple-value-bind (values text) (run-interaction "2")
    (is (null (first values)))
    (is (search "That's nice of you. Thanks!" text))))

(test pepper-not-found
  (multiple-value-bind (values text) (run-interaction "1 2" :remove '(:my-milk1 :my-milk2))
    (is (null (second values)))
    (is (search "Sorry I could not find your product" text))))

;;; The setups: descriptions, robot facts, Pepper on its feet, products on their levels.

(test tutorial-descriptions
  (btw-tut:init-projection)
  (is (equal "pr2" (cl-urdf:name (btw-tut:get-robot-urdf))))
  (is (equal "iai_kitchen" (cl-urdf:name (btw-tut:get-kitchen-urdf))))
  ;; a description that can be read from nowhere is an error naming the file, not NIL
  (signals roslisp-utilities:ros-utilities-error
    (btw-tut::read-urdf "no_such_description" "resources/no-such-file.urdf")))

(test pr2-forward-neck-fact
  (let ((states (cut:var-value '?s (cut:lazy-car
                                    (prolog:prolog '(rob-int:robot-joint-states
                                                     :pr2 :neck nil :forward ?s))))))
    (is (equal '(("head_pan_joint" 0.0d0) ("head_tilt_joint" 0.0d0)) states))))

(defun z-of (pose) (cl-transforms:z (cl-transforms:origin pose)))

(test pepper-stands-on-the-floor
  (demo:init-projection)
  (let ((pepper (btr:get-robot-object)))
    (is (equal "base_footprint" (cl-urdf:name (cl-urdf:root-link (btr:urdf pepper)))))
    (is (< (abs (z-of (btr:link-pose pepper "base_footprint"))) 1d-6))
    (is (< (abs (- 0.82d0 (z-of (btr:link-pose pepper "base_link")))) 1d-3))
    (is (< 1.0d0 (z-of (btr:camera-pose (btr:name pepper))) 1.15d0))
    ;; poses in the base frame (base_link) are placed at that link, not at the root
    (let ((p (pp-plans:pose-in-map (cl-transforms-stamped:make-pose-stamped
                                    "base_link" 0d0 (cl-transforms:make-3d-vector 0 0 0)
                                    (cl-transforms:make-identity-rotation)))))
      (is (< (abs (- 0.82d0 (z-of p))) 1d-3)))))

(test pepper-camera-sees-past-its-head
  (demo:init-projection)
  ;; right in the camera's view, where the inside of the head sphere around the camera was
  (prolog:prolog '(and (btr:bullet-world ?w)
                   (assert (btr:object ?w :mesh :probe ((2.0 -0.8 1.1) (0 0 0 1))
                                       :mass 0 :color (1 0 0) :mesh :milk))))
  (multiple-value-bind (fraction occluders)
      (btr:visibility-fraction (btr:camera-pose (rob-int:current-robot-name)) :probe)
    (is (> fraction 0.99))
    (is (null occluders))))

(test pepper-products-stand-on-levels
  (demo:init-projection)
  (demo:spawn-products-one)
  (loop for (name ((x y z))) in demo::*products*
        for object = (btr:object btr:*current-bullet-world* name)
        for origin = (cl-transforms:origin (btr:pose object))
        for bottom = (cl-transforms:z (btr:aabb object))
        for support = (pp-plans:support-height-below x y z :ignore (list name))
        do (is (< (abs (- x (cl-transforms:x origin))) 1d-6))
           (is (< (abs (- y (cl-transforms:y origin))) 1d-6))
           (is (<= (- support 1d-6) bottom (+ support 0.02d0))
               "~a: bottom ~,4f, level top ~,4f" name bottom support))
  ;; the seed's cereal box stands on level 2 of shelf 1 (top 0.951 m)
  (is (< (abs (- 0.9513d0 (cl-transforms:z (btr:aabb (btr:object btr:*current-bullet-world*
                                                                 :my-cereal1)))))
         2d-3)))

(test pepper-view-poses
  (demo:init-projection)
  (demo:spawn-products-one)
  (let ((shelf-two (find-if (lambda (p) (< (cl-transforms:x (cl-transforms:origin p)) 3))
                            (demo:get-shelf-pose 'demo::milk))))
    (is (not (null shelf-two)))
    ;; shelf 2 opens towards +y: the fallback pose stands there, facing -y
    (let ((pose (demo::facing-pose shelf-two 1.5d0)))
      (is (< (abs (- (+ (cl-transforms:y (cl-transforms:origin shelf-two)) 1.5d0)
                     (cl-transforms:y (cl-transforms:origin pose))))
             0.05d0))
      (is (< (abs (+ (/ pi 2) (cl-transforms:get-yaw (cl-transforms:orientation pose)))) 0.05d0)))
    ;; the seed's visibility designator: an object of type shelf qualifies what is seen, the
    ;; location says where
    (let* ((?pose (cl-transforms-stamped:pose->pose-stamped "map" 0 shelf-two))
           (?location (desig:a location (pose ?pose)))
           (?robot (rob-int:current-robot-name))
           (solution (desig:reference (desig:a location (visible-for ?robot) (location ?location)
                                               (object (desig:an object (type :shelf)))))))
      (is (< (cl-transforms:v-dist (cl-transforms:make-3d-vector
                                    (cl-transforms:x (cl-transforms:origin solution))
                                    (cl-transforms:y (cl-transforms:origin solution)) 0)
                                   (cl-transforms:make-3d-vector
                                    (cl-transforms:x (cl-transforms:origin shelf-two))
                                    (cl-transforms:y (cl-transforms:origin shelf-two)) 0))
             2.05d0)))
    (let ((pose (demo:generate-robot-pose shelf-two)))
      (is (demo::shelf-view-pose-p pose shelf-two)))
    ;; the fallback pose counts as a view pose of every shelf pose (it stands at the viewing
    ;; distance, which rounding may put a hair short)
    (dolist (shelf (append (demo:get-shelf-pose 'demo::milk) (demo:get-shelf-pose 'demo::cereal)))
      (is (demo::shelf-view-pose-p (demo::facing-pose shelf demo::*viewing-distance*) shelf)))))

(test init-projection-gives-a-fresh-world-each-time
  "INIT-PROJECTION copies the belief state it built before: what a run changed is gone."
  (btw-tut:init-projection)
  (let ((first btr:*current-bullet-world*))
    (btw-tut::spawn-bottle)
    (btw-tut:move-kitchen-joint :joint-name "iai_fridge_door_joint" :joint-angle 0.3d0)
    (setf (btr:pose (btr:get-robot-object))
          (cl-transforms:make-pose (cl-transforms:make-3d-vector 1 1 0) (cl-transforms:make-identity-rotation)))
    (btw-tut:init-projection)
    (let ((world btr:*current-bullet-world*))
      (is (not (eq first world)))
      (is (null (btr:object world 'btw-tut::bottle-1)))
      (is (< (abs (btr:joint-state (btr:object world btr:*environment-name*) "iai_fridge_door_joint")) 1d-9))
      (is (< (cl-transforms:v-norm (cl-transforms:origin (btr:pose (btr:get-robot-object)))) 1d-9))
      (is (equal (mapcar #'btr:name (btr:objects world))
                 (progn (setf btw-tut::*template* nil) (btw-tut:init-projection)
                        (mapcar #'btr:name (btr:objects btr:*current-bullet-world*))))))))
