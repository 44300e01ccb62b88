;;;; Tests of the reach memory of MOVE-TCP: a tool goal reached before in the same projection
;;;; run is reached again in the state found then, when that state is still free and the base
;;;; may go there; otherwise the search runs as before.

(in-package :cram-plans-tests.urdf-proj)

(in-suite urdf-proj)

(defparameter *memory-goal* (ps "map" -2.0 -0.75 0.95 (/ pi -2))
  "A goal of the right tool frame above the kitchen's table, reachable from *GRASP-BASE-POSE*.")

(defun robot-base-and-arm ()
  "The robot's base pose and its right arm's and torso's joint values."
  (let ((robot (robot)))
    (list (btr:pose robot)
          (mapcar (lambda (j) (btr:joint-state robot j))
                  (cons "torso_lift_joint" (rob-int:get-arm-joints :pr2 :right))))))

(defun same-base-and-arm-p (a b)
  (and (pose-near (first a) (first b) 1d-9)
       (every (lambda (x y) (near x y 1d-9)) (second a) (second b))))

(defmacro in-one-run (&body body)
  "BODY in the kitchen with the robot parked at *GRASP-BASE-POSE*, torso at 0.3, in one
projection run (one reach memory)."
  `(with-kitchen
     (urdf-proj:with-simulated-robot
       (urdf-proj:move-joints :park :park)
       (urdf-proj:drive *grasp-base-pose*)
       (urdf-proj:move-torso 0.3)
       ,@body)))

(test a-projection-run-starts-with-an-empty-reach-memory
  (with-kitchen
    (let ((first (urdf-proj:with-simulated-robot
                   (urdf-proj:move-joints :park :park)
                   (urdf-proj:drive *grasp-base-pose*)
                   (urdf-proj:move-torso 0.3)
                   (urdf-proj:move-tcp nil *memory-goal*)
                   urdf-proj::*reach-memory*))
          (second (urdf-proj:with-simulated-robot urdf-proj::*reach-memory*)))
      (is (= 1 (length (urdf-proj::reach-memory-entries first))))
      (is (not (eq first second)))
      (is (null (urdf-proj::reach-memory-entries second))))))

(test a-tool-goal-reached-before-is-reached-the-same-way-again
  (in-one-run
    (urdf-proj:move-tcp nil *memory-goal*)
    (let ((first-time (robot-base-and-arm)))
      (urdf-proj:move-joints :park :park)
      (is (not (same-base-and-arm-p first-time (robot-base-and-arm))))
      (multiple-value-bind (solves reached)
          (calls-during 'urdf-proj:solve-ik (lambda () (urdf-proj:move-tcp nil *memory-goal*)))
        (is (eq t reached))
        (is (= 0 solves) "~d IK solutions were searched for a goal reached before" solves))
      (is (same-base-and-arm-p first-time (robot-base-and-arm)))
      (is (null (urdf-proj:robot-collisions))))))

(test a-remembered-reach-that-collides-now-is-not-taken
  (in-one-run
    (urdf-proj:move-tcp nil *memory-goal*)
    (let* ((first-time (robot-base-and-arm))
           (elbow (cl-transforms:origin (btr:link-pose (robot) "r_forearm_link"))))
      (urdf-proj:move-joints :park :park)
      ;; a small box where the forearm was
      (btr:add-object btr:*current-bullet-world* :box 'memory-obstacle
                      (cl-transforms:make-pose elbow (cl-transforms:make-identity-rotation))
                      :size '(0.04 0.04 0.04) :mass 0)
      (unwind-protect
           (let ((reached (handler-case (urdf-proj:move-tcp nil *memory-goal*)
                            (common-fail:manipulation-low-level-failure () :failed))))
             (is (not (same-base-and-arm-p first-time (robot-base-and-arm))))
             (when (eq reached t)
               (is (null (urdf-proj:robot-collisions)))))
        (btr:remove-object btr:*current-bullet-world* 'memory-obstacle)))))

(test a-remembered-reach-beyond-the-base-offsets-is-not-taken
  (in-one-run
    (urdf-proj:move-tcp nil *memory-goal*)
    (let ((first-time (robot-base-and-arm)))
      (urdf-proj:move-joints :park :park)
      ;; 0.5 m further along the table: the remembered base is beyond the offsets
      (urdf-proj:drive (ps "map" -1.3547d0 -0.381d0 0 (/ pi -2)))
      (let ((base (btr:pose (robot))))
        (handler-case (urdf-proj:move-tcp nil *memory-goal*)
          (common-fail:manipulation-low-level-failure () nil))
        (is (not (same-base-and-arm-p first-time (robot-base-and-arm))))
        (is (<= (cl-transforms:v-dist (cl-transforms:origin base)
                                      (cl-transforms:origin (btr:pose (robot))))
                (+ (* (sqrt 2d0) 0.2d0) 1d-6)))))))
