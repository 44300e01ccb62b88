;;;; Switching two bottles: the red one from the table goes to the island, the green one from
;;;; the island to the table.

(in-package :cram-bullet-world-tutorial)

(defparameter *pose-bottle-1*
  (cl-transforms-stamped:make-pose-stamped
   "map" 0.0 (cl-transforms:make-3d-vector -2.0d0 -0.9d0 0.861667d0)
   (cl-transforms:make-identity-rotation))
  "Where bottle-1 (red) starts on the table, and where bottle-2 ends.")

(defparameter *pose-bottle-2*
  (cl-transforms-stamped:make-pose-stamped
   "map" 0.0 (cl-transforms:make-3d-vector -0.65d0 2.0d0 0.955d0)
   (cl-transforms:make-identity-rotation))
  "Where bottle-2 (green) starts on the kitchen island, and where bottle-1 ends.")

(defparameter *pose-meal-table*
  (cl-transforms-stamped:make-pose-stamped
   "map" 0.0 (cl-transforms:make-3d-vector -0.15d0 2.0d0 0.0d0)
   (cl-transforms:make-quaternion 0.0d0 0.0d0 -1.0d0 0.0d0))
  "Where the robot stands in front of the kitchen island (the meal table).")

(defparameter *pose-counter*
  (cl-transforms-stamped:make-pose-stamped
   "map" 0.0 (cl-transforms:make-3d-vector -1.8547d0 -0.381d0 0.0d0)
   (cl-transforms:axis-angle->quaternion (cl-transforms:make-3d-vector 0 0 1) (/ pi -2)))
  "Where the robot stands in front of the table (the counter).")

(defun spawn-two-bottles ()
  "Put the red BOTTLE-1 on the table and the green BOTTLE-2 on the island; let them settle."
  (unless (assoc :bottle btr:*mesh-files*)
    (add-objects-to-mesh-list))
  (prolog `(and (btr:bullet-world ?world)
                (assert (btr:object ?world :mesh bottle-1 ((-2 -0.9 0.861667d0) (0 0 0 1))
                                    :mass 0.2 :color (1 0 0) :mesh :bottle))
                (assert (btr:object ?world :mesh bottle-2 ((-0.65 2 0.955) (0 0 0 1))
                                    :mass 0.2 :color (0 1 0) :mesh :bottle))
                (btr:simulate ?world 100))))

(defun move-arm-out-of-sight (&key (arm '(:left :right)))
  "Park ARM (an arm or a list of arms)."
  (unless (listp arm) (setf arm (list arm)))
  (let ((?left (and (member :left arm) :park))
        (?right (and (member :right arm) :park)))
    (exe:perform (desig:an action (type positioning-arm)
                           (desig:when ?left (left-configuration ?left))
                           (desig:when ?right (right-configuration ?right))))))

(defun navigate-to (?navigation-goal)
  "Drive to the pose-stamped ?NAVIGATION-GOAL."
  (exe:perform (desig:an action (type going)
                         (target (desig:a location (pose ?navigation-goal))))))

(defun look-at (?point-of-interest)
  "Look at the pose-stamped ?POINT-OF-INTEREST."
  (exe:perform (desig:an action (type looking)
                         (target (desig:a location (pose ?point-of-interest))))))

(defun get-perceived-bottle-desig (&optional name)
  "Detect a bottle (named NAME when given) and return its designator."
  (let* ((?name name)
         (?bottle-desig (desig:an object (type bottle) (desig:when ?name (name ?name))))
         (?perceived-bottle-desig (exe:perform (desig:a motion (type detecting)
                                                        (object ?bottle-desig)))))
    ?perceived-bottle-desig))

(defun pick-up (?object-designator &optional (?arm :right))
  "Pick up ?OBJECT-DESIGNATOR with ?ARM."
  (exe:perform (desig:an action (type picking-up) (arm ?arm) (object ?object-designator))))

(defun place-down (?pose ?object ?arm)
  "Put ?OBJECT held by ?ARM at the pose-stamped ?POSE."
  (exe:perform (desig:an action (type placing) (arm ?arm) (object ?object)
                         (target (desig:a location (pose ?pose))))))

(defun move-to-reach (?object-designator ?grasping-arm)
  "Drive to where ?GRASPING-ARM reaches ?OBJECT-DESIGNATOR."
  (pp-plans::drive-towards-object-plan ?object-designator :arm ?grasping-arm))

(defun test-switch-two-bottles ()
  "Swap BOTTLE-1 (table) and BOTTLE-2 (island) in projection. Returns both designators."
  (spawn-two-bottles)
  (urdf-proj:with-simulated-robot
    (let ((?navigation-goal *pose-counter*)
          (?ptu-goal *downward-look-coordinate*))
      (cpl:par
        (exe:perform (desig:a motion (type moving-torso) (joint-angle 0.3)))
        (move-arm-out-of-sight)
        (navigate-to ?navigation-goal))
      (look-at ?ptu-goal)
      (let* ((?perceived-bottle-1 (get-perceived-bottle-desig 'bottle-1)))
        (move-to-reach ?perceived-bottle-1 :right)
        (pick-up ?perceived-bottle-1 :right)
        (move-arm-out-of-sight :arm :right)
        (navigate-to *pose-meal-table*)
        (look-at *downward-look-coordinate*)
        (let ((?perceived-bottle-2 (get-perceived-bottle-desig 'bottle-2)))
          (move-to-reach ?perceived-bottle-2 :left)
          (pick-up ?perceived-bottle-2 :left)
          (move-arm-out-of-sight :arm :left)
          (navigate-to *pose-meal-table*)
          (place-down *pose-bottle-2* ?perceived-bottle-1 :right)
          (move-arm-out-of-sight :arm :right)
          (navigate-to *pose-counter*)
          (place-down *pose-bottle-1* ?perceived-bottle-2 :left)
          (move-arm-out-of-sight)
          (list ?perceived-bottle-1 ?perceived-bottle-2))))))
