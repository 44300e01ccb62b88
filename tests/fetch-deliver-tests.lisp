;;;; Tests of the household action layer (FD-PLANS): searching, fetching and delivering from
;;;; given base poses, their failures and retries, in the kitchen of the belief state.

(defpackage :cram-plans-tests-fetch-deliver
  (:use :cl :fiveam)
  (:import-from :cram-plans-tests #:calls-during))

(in-package :cram-plans-tests-fetch-deliver)

(def-suite fetch-deliver :in cram-plans-tests:all
  :description "Searching, fetching, delivering and transporting (FD-PLANS).")
(in-suite fetch-deliver)

;;; Places and base poses in the kitchen (map frame).
(defparameter *island* '(-0.8 0.76 0.9))
(defparameter *sink* '(1.48 0.96 0.9))
(defparameter *in-fridge* '(1.48 -1.16 0.55) "Behind the closed fridge door.")
(defparameter *robot-at-island* (list -0.1 0.74 0 pi))
(defparameter *robot-at-wall* (list -0.1 2.2 0 pi))
(defparameter *robot-at-sink* '(0.8 0.7 0 0))
(defparameter *robot-in-sink* '(1.0 0.7 0 0)
  "A base pose overlapping the sink block: every navigation there is in collision.")

(defun pose (x y z &optional (yaw 0))
  (cl-transforms-stamped:make-pose-stamped
   "map" 0d0 (cl-transforms:make-3d-vector x y z)
   (cl-transforms:axis-angle->quaternion (cl-transforms:make-3d-vector 0 0 1) yaw)))

(defun poses-location (&rest places)
  "A location designator with the POSES of PLACES ((x y z [yaw])...)."
  (let ((?poses (mapcar (lambda (p) (apply #'pose p)) places)))
    (desig:a location (poses ?poses))))

(defun setup (place &key (type :bottle))
  "A fresh kitchen with the PR2 at the origin and one object of TYPE resting at PLACE."
  (btw-tut:init-projection)
  (destructuring-bind (x y z) place
    (btr:add-object btr:*current-bullet-world* :mesh :object-1
                    (cl-transforms:make-pose (cl-transforms:make-3d-vector x y z)
                                             (cl-transforms:make-identity-rotation))
                    :mesh type :mass 0.2 :types (list type)))
  (btr:simulate btr:*current-bullet-world* 1))

(defun object-position ()
  (cl-transforms:origin (btr:pose (btr:object btr:*current-bullet-world* :object-1))))

(defun run-plan (thunk)
  "Run THUNK in projection with the log captured: (values result-or-condition log)."
  (let* ((log (make-string-output-stream))
         (result (let ((cpl:*log-stream* log))
                   (handler-case (urdf-proj:with-simulated-robot (funcall thunk))
                     (serious-condition (c) c)))))
    (values result (get-output-stream-string log))))

(defun search-action (place robot-poses)
  (let ((?location (apply #'poses-location (list place)))
        (?robot (apply #'poses-location robot-poses)))
    (desig:an action (type searching) (object (desig:an object (type bottle)))
              (location ?location) (robot-location ?robot))))

(defun fetch-action (robot-poses &optional arms)
  (let ((?robot (apply #'poses-location robot-poses)) (?arms arms))
    (desig:an action (type fetching) (object (desig:an object (type bottle) (name object-1)))
              (robot-location ?robot) (desig:when ?arms (arms ?arms)))))

(defun deliver-action (targets robot-poses)
  (let ((?target (apply #'poses-location targets))
        (?robot (apply #'poses-location robot-poses)))
    (desig:an action (type delivering) (object (desig:an object (type bottle) (name object-1)))
              (target ?target) (robot-location ?robot))))

(defun held-p ()
  (fd-plans::object-held-p :object-1))

(test search-finds-the-object-in-view
  (setup *island*)
  (multiple-value-bind (result log) (run-plan (lambda () (exe:perform (search-action *island* (list *robot-at-island*)))))
    (is (typep result 'desig:object-designator) "search failed: ~a" result)
    (is (eq :object-1 (desig:desig-prop-value result :name)))
    ;; no failure is logged (the sweep check's warnings about the path are not failures)
    (is (notany (lambda (line) (and (search "WARN]" line) (not (search "(URDF-PROJ SWEEP)" line))))
                (uiop:split-string log :separator '(#\Newline)))
        "a happy search logs no failure:~%~a" log)
    ;; the robot stands where it was sent
    (is (< (cl-transforms:v-dist (cl-transforms:origin (btr:pose (btr:get-robot-object)))
                                 (cl-transforms:make-3d-vector -0.1 0.74 0))
           1d-3))))

(test search-for-an-object-behind-a-closed-door-fails
  (setup *in-fridge*)
  (multiple-value-bind (result log)
      (run-plan (lambda () (exe:perform (search-action *in-fridge*
                                                       (list *robot-at-wall* *robot-at-island*)))))
    (is (typep result 'common-fail:searching-failed) "got ~a" result)
    ;; both robot poses were tried
    (is (search "Retrying with the next solution of ?ROBOT-LOCATION" log))))

(test search-from-a-colliding-base-pose-fails-with-navigation-collision
  (setup *sink*)
  (multiple-value-bind (result log)
      (run-plan (lambda () (exe:perform (search-action *sink* (list *robot-in-sink*)))))
    (is (typep result 'common-fail:searching-failed) "got ~a" result)
    (is (search "NAVIGATION-GOAL-IN-COLLISION" log))
    ;; the pre-check never moved the robot into the sink
    (is (< (cl-transforms:v-norm (cl-transforms:origin (btr:pose (btr:get-robot-object)))) 1d-3))))

(test search-retries-the-next-robot-pose
  (setup *sink*)
  (multiple-value-bind (result log)
      (run-plan (lambda () (exe:perform (search-action *sink* (list *robot-in-sink* *robot-at-sink*)))))
    (is (typep result 'desig:object-designator) "got ~a" result)
    (is (search "collides with" log))
    ;; the robot stands at the second, free pose
    (is (< (cl-transforms:v-dist (cl-transforms:origin (btr:pose (btr:get-robot-object)))
                                 (cl-transforms:make-3d-vector 0.8 0.7 0))
           1d-3))))

(test fetch-from-the-island
  (setup *island*)
  (let ((result (run-plan (lambda () (exe:perform (fetch-action (list *robot-at-island*)))))))
    (is (typep result 'desig:object-designator) "fetch failed: ~a" result)
    (is (held-p))
    ;; the object left the island with the hand
    (is (> (cl-transforms:z (object-position)) 0.95))))

(test fetch-out-of-reach-fails
  (setup *island*)
  (let ((result (run-plan (lambda () (exe:perform (fetch-action (list *robot-at-wall*)))))))
    (is (typep result 'common-fail:fetching-failed) "got ~a" result)
    (is (not (held-p)))))

(test fetch-relocates-to-the-next-base-pose
  (setup *island*)
  (let ((result (run-plan (lambda () (exe:perform (fetch-action (list *robot-at-wall* *robot-at-island*)))))))
    (is (typep result 'desig:object-designator) "got ~a" result)
    (is (held-p))))

(defun fetched-at-island ()
  (setup *island*)
  (let ((result (run-plan (lambda () (exe:perform (fetch-action (list *robot-at-island*)))))))
    (unless (held-p) (error "The object could not be fetched for a delivery test: ~a" result))))

(test deliver-to-the-sink
  (fetched-at-island)
  (let ((result (run-plan (lambda () (exe:perform (deliver-action (list *sink*) (list *robot-at-sink*)))))))
    (is (typep result 'desig:object-designator) "got ~a" result)
    (is (not (held-p)))
    (is (< (cl-transforms:v-dist (object-position) (apply #'cl-transforms:make-3d-vector *sink*))
           0.08))))

(test deliver-to-an-unreachable-target-fails
  (fetched-at-island)
  (let ((result (run-plan (lambda () (exe:perform (deliver-action (list *sink*) (list *robot-at-island*)))))))
    (is (typep result 'common-fail:delivering-failed) "got ~a" result)
    (is (held-p) "the object stays in the hand")))

(test deliver-tries-the-next-target
  (fetched-at-island)
  (let ((result (run-plan (lambda () (exe:perform (deliver-action (list *sink* *island*)
                                                              (list *robot-at-island*)))))))
    (is (typep result 'desig:object-designator) "got ~a" result)
    (is (< (cl-transforms:v-dist (object-position) (apply #'cl-transforms:make-3d-vector *island*))
           0.08))))

(test bad-input-names-the-value
  (setup *island*)
  (signals desig:designator-error
    (desig:reference (desig:an action (type fetching) (object 42))))
  (signals desig:designator-error
    (desig:reference (desig:an action (type searching))))
  (let ((?location 'kitchen-table))
    (signals desig:designator-error
      (desig:reference (desig:an action (type navigating) (location ?location))))))

(test base-pose-verdicts-are-reused
  "Within WITH-BASE-POSE-VERDICTS a base pose judged once for the same checks and robot joints
is not checked again (the same verdict, ACCEPT not called); other checks, a moved torso or no
verdict table check it again."
  (setup *island*)
  (let ((calls 0)
        (free (pose 0.8 0.7 0 0)))
    (flet ((judge (what)
             (fd-plans::judge-base-pose free (lambda (p) (declare (ignore p)) (incf calls) nil)
                                        what)))
      (fd-plans::with-base-pose-verdicts ()
        (is (equal '(nil nil) (multiple-value-list (judge '(:a)))))
        (is (= 1 calls))
        (is (equal '(nil nil) (multiple-value-list (judge '(:a)))))
        (is (= 1 calls) "the second judgement of the same pose is the cached one")
        (judge '(:b))
        (is (= 2 calls) "other checks are judged anew")
        (let ((robot (btr:get-robot-object)))
          (setf (btr:joint-state robot "torso_lift_joint") 0.2d0)
          (judge '(:a))
          (is (= 3 calls) "a moved torso is judged anew")))
      (judge '(:a))
      (is (= 4 calls) "without a verdict table every judgement checks"))
    ;; a pose in collision is rejected with what it touches, ACCEPT not asked
    (fd-plans::with-base-pose-verdicts ()
      (multiple-value-bind (accepted hits)
          (fd-plans::judge-base-pose (apply #'pose *robot-in-sink*)
                                     (lambda (p) (declare (ignore p)) (incf calls) t) '(:c))
        (is (null accepted))
        (is (consp hits))
        (is (= 4 calls))))))

(test regrasp-check-of-a-placing-sample
  "An object put down on a surface must be graspable there again from where the robot stands
(FD-PLANS::OBJECT-REGRASPABLE-AT-P): true on the island in front of the robot, false at the
sink behind it; either way the held object ends where it was, attached to the same hand."
  (setup *island*)
  (let ((resting (btr:pose (btr:object btr:*current-bullet-world* :object-1))))
   (fetched-at-island)
   (let* ((robot (btr:get-robot-object))
         (attached (btr:attached-objects robot))
         (before (object-position))
         (object (desig:an object (type bottle) (name object-1))))
    (is (= 1 (length attached)) "the fetched object is held: ~s" attached)
    (flet ((unchanged-p ()
             (and (equal attached (btr:attached-objects robot))
                  (< (cl-transforms:v-dist before (object-position)) 1d-6))))
      (is (eq t (urdf-proj:with-simulated-robot
                  (fd-plans::object-regraspable-at-p object resting))))
      (is (unchanged-p) "the held object was put back after the check")
      ;; a later fetch limited to grasps the bottle has none of: not graspable again
      (let ((fd-plans::*regrasp-grasps* '((:bottle (:no-such-grasp)))))
        (is (equal '(:no-such-grasp) (fd-plans::regrasp-grasps object)))
        (is (null (urdf-proj:with-simulated-robot
                    (fd-plans::object-regraspable-at-p object resting)))))
      (let ((fd-plans::*regrasp-grasps* '((:cup (:no-such-grasp)))))
        (is (null (fd-plans::regrasp-grasps object)) "other types limit nothing")
        (is (eq t (urdf-proj:with-simulated-robot
                    (fd-plans::object-regraspable-at-p object resting)))))
      (is (null (urdf-proj:with-simulated-robot
                  (fd-plans::object-regraspable-at-p object
                                                     (pp-plans:pose-in-map (apply #'pose *sink*))))))
      (is (unchanged-p) "the held object was put back after the failed check"))))
  ;; which targets are checked: surfaces, not containers, attachments, ABOVE or given poses
  (let ((fd-plans::*check-regrasping* t)
        (?table (desig:an object (type counter-top) (urdf-name kitchen-island-surface)))
        (?in (desig:an object (type drawer) (urdf-name sink-area-left-upper-drawer-main))))
    (is (fd-plans::regrasp-check-target-p (desig:a location (on ?table))))
    (let ((?bowl (desig:an object (type bowl))))
      (is (fd-plans::regrasp-check-target-p (desig:a location (right-of ?bowl) (near ?bowl)))))
    (is (not (fd-plans::regrasp-check-target-p (poses-location *island*))))
    (is (not (fd-plans::regrasp-check-target-p (desig:a location (in ?in)))))
    (is (not (fd-plans::regrasp-check-target-p (desig:a location (above ?in)))))
    (let ((fd-plans::*check-regrasping* nil))
      (is (not (fd-plans::regrasp-check-target-p (desig:a location (on ?table))))))))

;;; Where an object was put down from, offered again to the fetch that takes it back.

(defun fetch-location-first-pose ()
  (let ((?robot (rob-int:current-robot-name)))
    (pp-plans:pose-in-map
     (desig:reference (desig:a location (reachable-for ?robot)
                               (object (desig:an object (type bottle) (name object-1))))))))

(test a-delivered-object-is-fetched-from-where-it-was-put-down
  (fetched-at-island)
  (let ((result (run-plan (lambda () (exe:perform (deliver-action (list *sink*) (list *robot-at-sink*)))))))
    (is (typep result 'desig:object-designator) "the delivery failed: ~a" result))
  (let ((put-from (cl-transforms:make-3d-vector 0.8 0.7 0)))
    (is (< (cl-transforms:v-dist (cl-transforms:origin (fetch-location-first-pose)) put-from) 1d-3)
        "the first base pose offered is where the robot put it down from")
    ;; the fetch drives there first (the pre-check judging it), for the arm it was put down with
    (let* ((arm (fd-plans::placing-arm (fd-plans::placing-record :object-1)))
           (other (if (eq arm :left) :right :left))
           (object (desig:an object (type bottle) (name object-1)))
           (first-location (fd-plans::placed-from-location object nil)))
      (is-true first-location)
      (when first-location
        (is (< (cl-transforms:v-dist (cl-transforms:origin (pp-plans:pose-in-map
                                                            (desig:reference first-location)))
                                     put-from)
               1d-3)))
      (is-true (fd-plans::placed-from-location object (list arm)))
      (is (null (fd-plans::placed-from-location object (list other)))))
    ;; moved by 5 cm: no longer offered
    (let ((o (btr:object btr:*current-bullet-world* :object-1)))
      (setf (btr:pose o) (cl-transforms:make-pose
                          (cl-transforms:v+ (cl-transforms:origin (btr:pose o))
                                            (cl-transforms:make-3d-vector 0 0.05 0))
                          (cl-transforms:orientation (btr:pose o)))))
    (is (null (fd-plans::placing-record :object-1)) "a moved object has no record")
    (is (> (cl-transforms:v-dist (cl-transforms:origin (fetch-location-first-pose)) put-from) 1d-3)
        "a moved object's fetch location starts with the costmap's samples"))
  ;; a new belief state remembers nothing
  (setup *island*)
  (is (null (fd-plans::placing-record :object-1))))

(test the-picking-up-pre-check-opens-the-gripper-as-the-action-does
  (setup *island*)
  (let* ((robot (btr:get-robot-object))
         (joints (urdf-proj::gripper-joints :left))
         (seen '()))
    (setf (btr:pose robot) (pp-plans:pose-in-map (apply #'pose *robot-at-island*)))
    ;; the gripper starts closed
    (btr:set-robot-state-from-joints
     (mapcar (lambda (j) (list j (btr:joint-limits robot j))) joints) robot)
    (let ((closed (btr:joint-state robot (first joints))))
      (sb-int:encapsulate 'fd-plans::trajectory-reachable-p 'record-gripper
                          (lambda (f arm &rest args)
                            (push (cons arm (btr:joint-state robot (first (urdf-proj::gripper-joints arm))))
                                  seen)
                            (apply f arm args)))
      (unwind-protect
           (urdf-proj:with-simulated-robot
             (fd-plans::check-picking-up-collisions
              (desig:an object (type bottle) (name object-1)) :arms '(:left)))
        (sb-int:unencapsulate 'fd-plans::trajectory-reachable-p 'record-gripper))
      (let* ((opening (man-int:get-object-type-gripper-opening :bottle))
             (multiplier (urdf-proj::fact-value '?m `(rob-int:gripper-meter-to-joint-multiplier
                                                      ,(rob-int:current-robot-name) ?m)))
             (expected (urdf-proj::clamp-joint robot (first joints) (* opening multiplier))))
        (is (consp seen) "the pre-check checked a grasp")
        (is (every (lambda (s) (< (abs (- (cdr s) expected)) 1d-9)) seen)
            "the gripper was open to ~,3f (the bottle's ~,3f m) while checked: ~s" expected opening seen)
        (is (> (abs (- expected closed)) 0.1) "open differs from closed")
        (is (< (abs (- (btr:joint-state robot (first joints)) closed)) 1d-9)
            "the gripper is closed again after the check")))))

(test only-attachment-poses-skip-the-stability-check
  ;; CRAM's always-stable locations are the predefined attachments; a costmap sample of the same
  ;; designator (taken when the attachment poses were rejected) is dropped in a copy first
  (btw-tut:init-projection)
  (let* ((?tray (desig:an object (type drawer) (urdf-name sink-area-dish-washer-tray-bottom)
                          (part-of iai-kitchen)))
         (target (desig:a location (above ?tray) (for (desig:an object (type spoon)))
                          (attachments (dish-washer-drawer-center))))
         (attachment (cl-transforms:origin
                      (pp-plans:pose-in-map (first (costmap::attachment-poses target))))))
    (is (< (cl-transforms:v-dist (cl-transforms:origin (pp-plans:pose-in-map (desig:reference target)))
                                 attachment)
           1d-6)
        "the first solution is the attachment pose")
    (is-true (fd-plans::solution-stable-p target) "the attachment pose needs no stability check")
    (let ((sample (loop for s = (desig:next-solution target) then (desig:next-solution s)
                        repeat 5 while s
                        when (> (cl-transforms:v-dist (cl-transforms:origin
                                                       (pp-plans:pose-in-map (desig:reference s)))
                                                      attachment)
                                1d-3)
                          return s)))
      (is-true sample "a later solution is a costmap sample away from the attachment")
      (when sample
        (is (null (fd-plans::solution-stable-p sample)) "a costmap sample is checked")))
    (is-true (fd-plans::solution-stable-p (desig:a location (above ?tray)))
             "an ABOVE target without attachments needs no check (dropping into it is the point)")))

(test a-place-inside-another-body-is-taken
  ;; a held object let go where it reaches into a wall is thrown out by the physics: the
  ;; placing pre-check sees it (FD-PLANS::OBJECT-PENETRATIONS); the surface it rests on and
  ;; the robot holding it do not count
  (setup *island*)
  (let ((resting (btr:pose (btr:object btr:*current-bullet-world* :object-1))))
    (fetched-at-island)
    (let ((object (desig:an object (type bottle) (name object-1)))
          (before (object-position))
          (attached (btr:attached-objects (btr:get-robot-object))))
      (is (null (urdf-proj:with-simulated-robot (fd-plans::object-penetrations object resting)))
          "where it stood on the island, it reaches into nothing")
      (let ((inside (urdf-proj:with-simulated-robot
                      (fd-plans::object-penetrations object (pp-plans:pose-in-map
                                                             (apply #'pose *in-fridge*))))))
        (is (consp inside) "behind the closed fridge door it is inside the fridge: ~s" inside)
        (is (every (lambda (hit) (eq :iai-kitchen (first hit))) inside)))
      (is (< (cl-transforms:v-dist before (object-position)) 1d-6) "the object was put back")
      (is (equal attached (btr:attached-objects (btr:get-robot-object))) "and is held again"))))

(test an-object-counts-at-a-costmap-location-within-the-proximity
  ;; OBJECT-AT-LOCATION against a costmap: inside it, or within FD-PLANS::*LOCATION-PROXIMITY*
  ;; (5 cm) of its places, as a released object settles; farther off it does not hold
  (setup *island*)
  (let* ((island (btr:link-pose (btr:get-environment-object) "kitchen_island_surface"))
         (centre (cl-transforms:origin island))
         (o (btr:object btr:*current-bullet-world* :object-1))
         (z (cl-transforms:z (object-position)))
         (location (desig:a location
                            (on (desig:an object (type counter-top) (urdf-name kitchen-island-surface)
                                          (part-of iai-kitchen)))
                            (for (desig:an object (type bottle)))
                            (range 0.2))))
    (flet ((at (dx)
             (setf (btr:pose o) (cl-transforms:make-pose
                                 (cl-transforms:make-3d-vector (+ (cl-transforms:x centre) dx)
                                                               (cl-transforms:y centre) z)
                                 (cl-transforms:make-identity-rotation)))
             (costmap:forget-designator-costmap location)
             (fd-plans::object-at-location-p :object-1 location)))
      (is-true (at 0.1) "inside the range")
      (is-true (at 0.235) "3.5 cm beyond the range (its cell lies outside it): within the proximity")
      (is (null (at 0.35)) "15 cm beyond the range"))))

(test placing-verdicts-hold-across-target-samples
  ;; a delivery's base pose verdicts are kept by the target's description, not by its current
  ;; sample: a retry with the next sample does not check the same base poses again
  (setup *island*)
  (let* ((target (poses-location *sink* *island*))
         (next (desig:next-solution target))
         (object (desig:an object (type bottle) (name object-1))))
    (is-true next "the target has a second sample")
    (is (equal (fd-plans::place-key (list object :left target))
               (fd-plans::place-key (list object :left next))))
    (is (not (equal (fd-plans::place-key (list object :left target))
                    (fd-plans::place-key (list object :right target))))
        "the arm counts")))

(test pre-checks-check-paths-only-where-a-sweep-fails-the-motion
  ;; a pre-check's motions are hypothetical: under :WARN their paths are not checked (nor
  ;; reported: the performed motion reports its own); under :FAIL they are, as the motion
  ;; would fail on them
  (setup *island*)
  (setf (btr:pose (btr:get-robot-object)) (pp-plans:pose-in-map (apply #'pose *robot-at-island*)))
  (let ((calls 0))
    (sb-int:encapsulate 'urdf-proj:robot-sweeps 'count-calls
                        (lambda (f &rest args) (incf calls) (apply f args)))
    (unwind-protect
         (flet ((check (mode)
                  (setf calls 0)
                  (let ((urdf-proj:*sweep-check* mode))
                    ;; whether a grasp is found does not matter here
                    (handler-case
                        (urdf-proj:with-simulated-robot
                          (fd-plans::check-picking-up-collisions
                           (desig:an object (type bottle) (name object-1))))
                      (common-fail:object-unreachable () nil)))
                  calls))
           (is (= 0 (check :warn)) "no path checked under :warn")
           (is (plusp (check :fail)) "paths checked under :fail"))
      (sb-int:unencapsulate 'urdf-proj:robot-sweeps 'count-calls))))

(test pre-checks-solve-ik-with-fewer-restarts-than-the-motions
  ;; the coarse pre-checks give each IK call *PRECHECK-IK-RESTARTS* random restarts, the
  ;; motions URDF-PROJ::*REACH-IK-RESTARTS*
  (setup *island*)
  (setf (btr:pose (btr:get-robot-object)) (pp-plans:pose-in-map (apply #'pose *robot-at-island*)))
  (let ((restarts '()))
    (sb-int:encapsulate 'urdf-proj::chain-ik-from-map 'note-restarts
                        (lambda (f &rest args) (push (car (last args)) restarts) (apply f args)))
    (unwind-protect
         (flet ((restarts-of (coarse)
                  (setf restarts '())
                  (handler-case
                      (urdf-proj:with-simulated-robot
                        (fd-plans::check-picking-up-collisions
                         (desig:an object (type bottle) (name object-1)) :any (and coarse :coarse)))
                    (common-fail:object-unreachable () nil))
                  (remove-duplicates restarts)))
           (is (equal (list fd-plans::*precheck-ik-restarts*) (restarts-of t)))
           (is (equal (list urdf-proj::*reach-ik-restarts*) (restarts-of nil)))
           (is (< fd-plans::*precheck-ik-restarts* urdf-proj::*reach-ik-restarts*)))
      (sb-int:unencapsulate 'urdf-proj::chain-ik-from-map 'note-restarts))))

(test a-location-next-to-an-object-is-certain-once-the-object-was-found
  (setup *island*)
  (let* ((?object (desig:an object (type bottle)))
         (location (desig:a location (right-of ?object) (near ?object))))
    (is (not (fd-plans::location-certain-p location)) "not before the bottle was perceived")
    (let ((?location (poses-location *island*)) (?robot (poses-location *robot-at-island*)))
      (is (typep (run-plan (lambda ()
                             (exe:perform (desig:an action (type searching) (object ?object)
                                                    (location ?location) (robot-location ?robot)))))
                 'desig:object-designator)
          "the search found the bottle"))
    (is-true (fd-plans::location-certain-p location) "certain once it was perceived")))

(test the-sample-the-navigation-check-accepted-is-tried-first
  ;; navigating to deliver checks, at each base pose, whether the object can be put down at a
  ;; sample of the target from there; the sample it found is the one the delivery tries first
  ;; from that pose, once, instead of drawing new samples that may all fail
  (fetched-at-island)
  (let* ((target (poses-location *sink* *island*))
         (object (desig:an object (type bottle) (name object-1)))
         (arm (second (first (pp-plans::held-objects))))
         (fd-plans::*placing-hint* (list nil))
         hint again)
    (run-plan (lambda ()
                (fd-plans::navigate :location (poses-location *robot-at-island*)
                                    :place (list object arm target))
                (setf hint (fd-plans::take-placing-hint)
                      again (fd-plans::take-placing-hint))))
    (is-true hint "the check left the sample it accepted")
    (is (null again) "a hint is used once")
    (when hint
      ;; the sink is out of reach from the island: the accepted sample is the island's
      (is (< (cl-transforms:v-dist (cl-transforms:origin (pp-plans:pose-in-map hint))
                                   (apply #'cl-transforms:make-3d-vector *island*))
             0.05))
      (multiple-value-bind (at hinted) (fd-plans::check-placing-collisions object arm target
                                                                           :first hint)
        (is-true hinted)
        (is (< (cl-transforms:v-dist (cl-transforms:origin (pp-plans:pose-in-map (desig:reference at)))
                                     (cl-transforms:origin (pp-plans:pose-in-map hint)))
               1d-6)))
      ;; a hint holds only where it was found
      (setf (car fd-plans::*placing-hint*)
            (cons (apply #'pose *robot-at-sink*) hint))
      (is (null (fd-plans::take-placing-hint))))))

(test the-first-sample-that-scores-best-is-taken
  (btw-tut:init-projection)
  (flet ((x-of (d) (and d (cl-transforms:x (cl-transforms:origin
                                            (pp-plans:pose-in-map (desig:reference d))))))
         (target () (poses-location '(0.5 0 0.9) '(1.5 0 0.9) '(1.0 0 0.9))))
    (let ((score (lambda (d) (if (> (x-of d) 0.7) 1 0))))
      (is (= 0.5 (x-of (fd-plans::find-placing-sample (constantly t) (target) 3)))
          "without a score, the first that passes")
      (is (= 1.5 (x-of (fd-plans::find-placing-sample (constantly t) (target) 3
                                                      :score score :best 1))))
      (is (= 1.0 (x-of (fd-plans::find-placing-sample (lambda (d) (/= (x-of d) 1.5)) (target) 3
                                                      :score score :best 1)))
          "the first that passes and scores best")
      (is (= 0.5 (x-of (fd-plans::find-placing-sample (constantly t) (target) 3
                                                      :score (constantly 0) :best 1)))
          "none scores best: the first with the highest score")
      (is (null (fd-plans::find-placing-sample (constantly t) (target) 3
                                               :score (constantly 0) :best 1 :require-best t)))
      (is (null (fd-plans::find-placing-sample (constantly nil) (target) 3
                                               :score score :best 1)))
      ;; the final test: asked only of a sample its score would let be taken, with the same
      ;; answers as a predicate that asks it of every sample
      (let ((asked '()))
        (flet ((final (d) (push (x-of d) asked) (/= (x-of d) 1.5))
               (x-list (d) (x-of d)))
          (is (= 1.0 (x-list (fd-plans::find-placing-sample (constantly t) (target) 3
                                                            :score score :best 1 :final #'final))))
          (is (equal '(1d0 1.5d0) asked)
              "only the samples that score best, while one of them may still be taken: ~s" asked)
          (setf asked '())
          (is (= 0.5 (x-list (fd-plans::find-placing-sample (constantly t) (target) 3
                                                            :score (constantly 0) :best 1
                                                            :final #'final))))
          (is (equal '(0.5d0) asked) "after the first, no sample scores higher: ~s" asked)
          (setf asked '())
          (is (= 1.0 (x-list (fd-plans::find-placing-sample (lambda (d) (/= (x-of d) 0.5))
                                                            (target) 3 :final #'final))))
          (is (equal '(1d0 1.5d0) asked) "without a score, each that passes the predicate")
          ;; none scores best: the highest score first (1.5 and 1.0 score 1, 0.5 scores 0)
          (setf asked '())
          (is (= 1.0 (x-list (fd-plans::find-placing-sample (constantly t) (target) 3
                                                            :score score :best 2
                                                            :final #'final))))
          (is (equal '(1d0 1.5d0) asked) "the highest scores first, until one passes: ~s" asked)
          ;; under REQUIRE-BEST, that one is found only when asked for
          (setf asked '())
          (multiple-value-bind (found fallback)
              (fd-plans::find-placing-sample (constantly t) (target) 3 :score score :best 2
                                                                       :require-best t
                                                                       :final #'final)
            (is (null found))
            (is (null asked) "nothing asked before the fallback is: ~s" asked)
            (is (functionp fallback))
            (is (= 1.0 (x-list (funcall fallback))))
            (is (equal '(1d0 1.5d0) asked) "asked when the fallback is: ~s" asked))
          (is (equal '(nil nil)
                     (multiple-value-list
                      (fd-plans::find-placing-sample (constantly nil) (target) 3 :score score
                                                     :best 2 :require-best t :final #'final)))
              "no fallback when no sample passes the predicate"))))))

(test an-object-is-put-down-leaving-room-for-the-objects-that-follow
  ;; a cup will go within 6 cm of the island's origin: the bottle put down there, or 5 cm
  ;; beside it, leaves it no room; 30 cm away, it does
  (fetched-at-island)
  (let* ((origin (cl-transforms:origin (btr:link-pose (btr:get-environment-object)
                                                      "kitchen_island_surface")))
         (ox (cl-transforms:x origin)) (oy (cl-transforms:y origin))
         (?surface (desig:an object (type counter-top) (urdf-name kitchen-island-surface)
                             (part-of iai-kitchen)))
         (?cup (desig:an object (type cup)))
         (fd-plans::*places-to-leave* (list (desig:a location (on ?surface) (for ?cup)
                                                     (range 0.06))))
         (bottle (desig:an object (type bottle) (name object-1))))
    (setf (btr:pose (btr:get-robot-object))
          (cl-transforms:make-pose (cl-transforms:make-3d-vector ox (- oy 0.55) 0)
                                   (cl-transforms:axis-angle->quaternion
                                    (cl-transforms:make-3d-vector 0 0 1) (/ pi 2))))
    (flet ((room-after (dx dy)
             (fd-plans::room-left bottle (poses-location (list (+ ox dx) (+ oy dy) 0.9)))))
      (is (= 0 (room-after 0 0)))
      (is (= 0 (room-after 0 0.05)))
      (is (= 1 (room-after 0.3 0)))
      (is (= 1 (room-after -0.3 0)))
      (is (< (cl-transforms:v-dist (cl-transforms:origin (btr:pose (btr:get-robot-object)))
                                   (cl-transforms:make-3d-vector ox (- oy 0.55) 0))
             1d-9)
          "the robot is put back")
      (is-true (btr:attached-objects (btr:get-robot-object)) "the bottle is held again")))
  (let ((fd-plans::*deliveries-to-come* '(:milk :cup :spoon)))
    (is (= 3 (length (fd-plans::later-places nil :table-setting)))
        "the places of the milk, the cup and the spoon on the table"))
  (let ((fd-plans::*deliveries-to-come* '(:milk :bowl)))
    (is (null (fd-plans::later-places nil :table-cleaning))
        "the trash drawer and the dishwasher tray are no places on a surface")))

(test a-spoon-held-hanging-is-judged-where-it-comes-to-rest
  ;; the re-grasp check judges a spoon put down from a hand that holds it hanging where it will
  ;; lie, on the surface, not at the height its tip hangs down to
  (btw-tut:init-projection)
  (flet ((spawn (name turn)
           (btr:add-object btr:*current-bullet-world* :mesh name
                           (cl-transforms:make-pose (cl-transforms:make-3d-vector 0 -3 1.5)
                                                    (cl-transforms:axis-angle->quaternion
                                                     (cl-transforms:make-3d-vector 0 1 0) turn))
                           :mesh :spoon :mass 0.1 :types '(:spoon)))
         (drop (name)
           (let ((?name name))
             (- 0.9d0 (cl-transforms:z (cl-transforms:origin
                                        (fd-plans::resting-pose
                                         (desig:an object (type spoon) (name ?name))
                                         (cl-transforms:make-pose
                                          (cl-transforms:make-3d-vector 1 1 0.9)
                                          (cl-transforms:make-identity-rotation)))))))))
    (spawn :hanging-spoon (/ pi 2))
    (spawn :lying-spoon 0)
    (is (< 0.085 (drop :hanging-spoon) 0.11) "half its length less half its thickness")
    (is (< (drop :lying-spoon) 0.02))))

(test a-check-without-room-answers-from-the-check-with-room-at-the-same-base-pose
  ;; a cup's place within 6 cm of the island's origin is beyond the reach of a robot standing
  ;; at the island's end: no place leaves it room there. The check that requires room keeps
  ;; what it would have taken without, and the check without the requirement at the same base
  ;; pose answers from that
  (fetched-at-island)
  (let* ((?surface (desig:an object (type counter-top) (urdf-name kitchen-island-surface)
                             (part-of iai-kitchen)))
         (?cup (desig:an object (type cup)))
         (fd-plans::*places-to-leave* (list (desig:a location (on ?surface) (for ?cup)
                                                     (range 0.06))))
         (bottle (desig:an object (type bottle) (name object-1)))
         (arm (first (pp-plans::arms-holding :object-1)))
         (target (poses-location *island* (mapcar #'+ *island* '(0 0.05 0))))
         (base (apply #'pose *robot-at-island*)))
    (flet ((check (require-room)
             (let ((fd-plans::*require-room* require-room))
               (multiple-value-bind (calls result)
                   (calls-during 'fd-plans::placeable-at-p
                                 (lambda () (fd-plans::object-placeable-from-p bottle arm target base)))
                 (list calls result)))))
      (let ((unchecked (second (check nil))))
        (is-true unchecked "the bottle can be put down at the island from there")
        (fd-plans::with-base-pose-verdicts ()
          (destructuring-bind (calls result) (check t)
            (is (null result) "no place leaves room")
            (is (plusp calls)))
          (is (functionp (fd-plans::base-pose-verdict
                          (fd-plans::placing-fallback-key bottle arm target base)))
              "what it would have taken is kept to be found when asked for")
          (destructuring-bind (calls result) (check nil)
            (is (= 0 calls) "answered from the check that required room")
            (is (and result unchecked
                     (< (cl-transforms:v-dist (cl-transforms:origin (pp-plans:pose-in-map result))
                                              (cl-transforms:origin (pp-plans:pose-in-map unchecked)))
                        1d-6))
                "the same place as a check of its own takes")))))))

(test a-check-for-any-grasp-tries-the-coarse-candidates-first
  ;; the bottle on the island: some grasp is reachable from the island's end, none from the
  ;; sink; the check for any grasp finds one with fewer IK solutions than the full check needs
  ;; for the first reachable grasp, and that grasp passes the full check
  (setup *island*)
  (let ((bottle (desig:an object (type bottle) (name object-1)))
        (robot (btr:get-robot-object)))
    (setf (btr:pose robot) (pp-plans:pose-in-map (apply #'pose *robot-at-island*)))
    (multiple-value-bind (coarse-solves found)
        (calls-during 'urdf-proj:solve-ik
                      (lambda () (fd-plans::check-picking-up-collisions bottle :any t)))
      (destructuring-bind (arm grasp) found
        (is (equal found (fd-plans::check-picking-up-collisions bottle :arms (list arm)
                                                                       :grasps (list grasp)))
            "the grasp found passes the full check"))
      (let ((full-solves (calls-during 'urdf-proj:solve-ik
                                       (lambda () (fd-plans::check-picking-up-collisions bottle)))))
        (is (<= coarse-solves full-solves) "~d IK solutions with the coarse candidates first, ~d without"
            coarse-solves full-solves)))
    (is (equal (fd-plans::check-picking-up-collisions bottle :any :coarse)
               (fd-plans::check-picking-up-collisions bottle :any t))
        "the coarse candidates alone find the same grasp here")
    (setf (btr:pose robot) (pp-plans:pose-in-map (apply #'pose *robot-at-sink*)))
    (signals common-fail:object-unreachable
      (fd-plans::check-picking-up-collisions bottle :any t))
    (signals common-fail:object-unreachable
      (fd-plans::check-picking-up-collisions bottle :any :coarse))))
