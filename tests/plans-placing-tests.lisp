;;;; Tests of placing as CRAM does it: the object comes from the hand when the action names
;;;; none, the target defaults to where the object was picked up from, and a placed object
;;;; comes to rest on its surface (stable, in contact with it, at the target).

(defpackage :cram-plans-tests-placing
  (:use :cl :fiveam))

(in-package :cram-plans-tests-placing)

(def-suite placing :in cram-plans-tests:all :description "Placing: object from the hand, resting; the tutorial's costmap metadata.")
(in-suite placing)

(defun obj (name) (btr:object btr:*current-bullet-world* name))
(defun xyz (pose)
  (let ((o (cl-transforms:origin pose)))
    (list (cl-transforms:x o) (cl-transforms:y o) (cl-transforms:z o))))
(defun xy-distance (a b)
  (sqrt (+ (expt (- (first a) (first b)) 2) (expt (- (second a) (second b)) 2))))
(defun answers (query) (cut:force-ll (prolog:prolog query)))
(defun stable-p (name) (answers `(and (btr:bullet-world ?w) (btr:stable ?w ,name))))
(defun touches-kitchen-p (name) (answers `(and (btr:bullet-world ?w) (btr:contact ?w ,name :iai-kitchen))))
(defun bottom-z (name) (cl-transforms:z (nth-value 0 (btr:aabb (obj name)))))

(defun link-top (link)
  "The top (z) of the kitchen link LINK's bounding box."
  (let* ((env (obj :iai-kitchen))
         (index (position link (btr:link-names env) :test #'string=)))
    (cl-transforms:z (nth-value 1 (btr:aabb env index)))))

(defun attached-to-robot-p (name)
  (member name (btr:attached-objects (btr:get-robot-object)) :key #'first))

(defmacro quietly (&body body)
  `(let ((cpl:*log-stream* (make-broadcast-stream))) ,@body))

(defun pick-up-bottle-1 ()
  "In the current projection: drive to the counter, detect BOTTLE-1 and pick it up with the
right arm. Returns the bottle's pose before the pick-up."
  (let ((before (btr:pose (obj 'btw-tut::bottle-1))))
    (let ((?goal btw-tut:*pose-counter*) (?look btw-tut:*downward-look-coordinate*))
      (exe:perform (desig:a motion (type moving-torso) (joint-angle 0.3)))
      (btw-tut::move-arm-out-of-sight)
      (btw-tut:navigate-to ?goal)
      (btw-tut:look-at ?look))
    (let ((bottle (btw-tut:get-perceived-bottle-desig 'btw-tut::bottle-1)))
      (btw-tut:move-to-reach bottle :right)
      (btw-tut:pick-up bottle :right))
    before))

(test switched-bottles-rest-on-their-surfaces
  (btw-tut:init-projection)
  (let ((value (quietly (btw-tut:test-switch-two-bottles))))
    (is (listp value) "switching failed: ~a" value)
    (let ((island (link-top "kitchen_island_surface")))
      ;; bottle-1 went to the island: on it, at the target, stable, in contact
      (is (< (xy-distance (xyz (btr:pose (obj 'btw-tut::bottle-1))) (xyz btw-tut:*pose-bottle-2*)) 0.03))
;; resting: the bounding boxes carry a 1 mm margin, so a bottle on the surface has its
      ;; box bottom about 1 mm below the surface box top; one hovering 2 mm above fails
      (is (< (abs (- (bottom-z 'btw-tut::bottle-1) island)) 0.0015)
          "bottle-1's bottom is at ~,3f, the island top at ~,3f" (bottom-z 'btw-tut::bottle-1) island)
      (is-true (touches-kitchen-p 'btw-tut::bottle-1) "bottle-1 does not touch the kitchen")
      (is-true (stable-p 'btw-tut::bottle-1) "bottle-1 is not stable")
      ;; bottle-2 went to the table
      (is (< (xy-distance (xyz (btr:pose (obj 'btw-tut::bottle-2))) (xyz btw-tut:*pose-bottle-1*)) 0.03))
      (is-true (touches-kitchen-p 'btw-tut::bottle-2) "bottle-2 does not touch the kitchen")
      (is-true (stable-p 'btw-tut::bottle-2) "bottle-2 is not stable")
      (is (null (attached-to-robot-p 'btw-tut::bottle-1)))
      (is (null (attached-to-robot-p 'btw-tut::bottle-2))))))

(test placing-takes-the-object-from-the-hand-and-puts-it-back
  (btw-tut:init-projection)
  (btw-tut:spawn-two-bottles)
  (let (before placed held lifted)
    (quietly
      (urdf-proj:with-simulated-robot
        (setf before (pick-up-bottle-1)
              held (attached-to-robot-p 'btw-tut::bottle-1)
              lifted (cl-transforms:v-dist (cl-transforms:origin (btr:pose (obj 'btw-tut::bottle-1)))
                                           (cl-transforms:origin before)))
        ;; neither OBJECT nor TARGET: what the right hand holds goes back where it was
        (setf placed (exe:perform (desig:an action (type placing) (arm :right))))))
    (is-true held "bottle-1 was not in the hand")
    (is (> lifted 0.05) "bottle-1 was not lifted")
    (is (typep placed 'desig:object-designator) "placing returned ~s" placed)
    (is (string= "BOTTLE-1" (symbol-name (desig:desig-prop-value placed :name))))
    (is (null (attached-to-robot-p 'btw-tut::bottle-1)) "bottle-1 is still in the hand")
    (let ((now (xyz (btr:pose (obj 'btw-tut::bottle-1)))))
      (is (< (xy-distance now (xyz before)) 0.02) "bottle-1 is at ~a, it was at ~a" now (xyz before))
      (is (< (abs (- (third now) (third (xyz before)))) 0.01) "bottle-1 is at ~a, it was at ~a" now (xyz before)))
    (is-true (touches-kitchen-p 'btw-tut::bottle-1))
    (is-true (stable-p 'btw-tut::bottle-1))))

(test released-object-falls-onto-the-surface-below
  ;; a bottle let go 4 cm above the island comes to rest on it
  (btw-tut:init-projection)
  (btw-tut:spawn-two-bottles)
  (let* ((name 'btw-tut::bottle-2)
         (island (link-top "kitchen_island_surface"))
         (rest-z (cl-transforms:z (cl-transforms:origin (btr:pose (obj name))))))
    (btr-utils:move-object name (cl-transforms:make-pose
                                 (cl-transforms:make-3d-vector -0.9 1.5 (+ rest-z 0.04))
                                 (cl-transforms:make-identity-rotation)))
    (is (> (- (bottom-z name) island) 0.035))
    (is (null (stable-p name)) "a hovering bottle counts as stable")
    (pp-plans::settle-released-object name)
    (is (< (abs (- (bottom-z name) island)) 0.0015) "bottom at ~,3f, island top ~,3f" (bottom-z name) island)
    (is (< (xy-distance (xyz (btr:pose (obj name))) '(-0.9 1.5)) 0.01))
    (is-true (stable-p name))))

(test an-object-held-on-its-side-is-put-down-on-the-surface-not-into-it
  ;; a cup hanging on its side (as from a hand parked for carrying), put down upright with its
  ;; origin too low: the put-down pose is raised by its upright bottom offset, not by the
  ;; smaller one of its box as it hangs now
  (btw-tut:init-projection)
  (let* ((island (link-top "kitchen_island_surface"))
         (w btr:*current-bullet-world*))
    (btr:add-object w :mesh :cup-9
                    (cl-transforms:make-pose (cl-transforms:make-3d-vector -0.9 1.2 1.4)
                                             (cl-transforms:axis-angle->quaternion
                                              (cl-transforms:make-3d-vector 1 0 0) (/ pi 2)))
                    :mesh :cup :mass 0.2 :types '(:cup))
    (let* ((cup (obj :cup-9))
           (upright-bottom (- (cl-transforms:z (nth-value 0 (btr:local-aabb cup)))))
           (hanging-bottom (- 1.4d0 (bottom-z :cup-9)))
           (?pose (cl-transforms-stamped:make-pose-stamped
                   "map" 0d0 (cl-transforms:make-3d-vector -0.9 1.2 (+ island 0.01d0))
                   (cl-transforms:make-identity-rotation)))
           (goal (pp-plans::placing-target-pose (desig:an object (type cup) (name cup-9)) :cup
                                                (desig:a location (pose ?pose))))
           (z (cl-transforms:z (cl-transforms:origin (pp-plans:pose-in-map goal)))))
      (is (> (- upright-bottom hanging-bottom) 0.02)
          "the cup stands taller (~,3f) than it hangs (~,3f)" upright-bottom hanging-bottom)
      (is (<= (+ island upright-bottom -0.002d0) z (+ island upright-bottom 0.012d0))
          "put down at ~,3f; the island top is ~,3f, the cup's bottom ~,3f below its origin"
          z island upright-bottom)
      (is (< (abs (- (pp-plans::bottom-offset-at cup (cl-transforms:make-identity-rotation))
                     upright-bottom))
             1d-9)))))

(test placing-bad-input-names-the-value
  (btw-tut:init-projection)
  (btw-tut:spawn-two-bottles)
  (flet ((placing-error (designator)
           (quietly (urdf-proj:with-simulated-robot
                      (handler-case (progn (exe:perform designator) nil)
                        (error (e) (princ-to-string e)))))))
    ;; nothing in hand
    (let ((e (placing-error (desig:an action (type placing) (arm :right)))))
      (is (stringp e) "placing with an empty hand succeeded")
      (is (search ":RIGHT arm holds nothing" (or e "")) "~a" e))
    ;; an object that is not a designator
    (let ((e (placing-error (desig:an action (type placing) (arm :right) (object bottle-1)))))
      (is (stringp e) "placing a symbol succeeded")
      (is (search "BOTTLE-1" (or e "")) "~a" e)
      (is (search "expected an object designator" (or e "")) "~a" e))))

;;; The bullet_world tutorial's costmap metadata, typed with the short names in BTW-TUT

(test costmap-metadata-typed-in-the-users-package-is-used
  (let ((*package* (find-package "BTW-TUT")))
    (unwind-protect
         (progn
           (eval (read-from-string "(def-fact-group placing-tests-costmap-metadata ()
                                      (<- (costmap-in-reach-distance 0.7))
                                      (<- (orientation-samples 2)))"))
           (is (not (eq (find-symbol "COSTMAP-IN-REACH-DISTANCE" "BTW-TUT")
                        'costmap:costmap-in-reach-distance))
               "the test needs the user's own symbol")
           (let ((rob-int:*robot-name* :pr2))
             (is (= 0.7 (costmap:costmap-metadata-value 'costmap:costmap-in-reach-distance)))
             (is (= 2 (costmap:costmap-metadata-value 'costmap:orientation-samples)))
             ;; what the user did not state still comes from the robot
             (is (= 0.3 (costmap:costmap-metadata-value 'costmap:costmap-padding)))))
      (prolog:remove-fact-group (find-symbol "PLACING-TESTS-COSTMAP-METADATA" "BTW-TUT"))))
  (let ((rob-int:*robot-name* :pr2))
    (is (= 1.05 (costmap:costmap-metadata-value 'costmap:costmap-in-reach-distance))
        "without the user's group the PR2's own reach answers")))

(test a-flat-object-is-grasped-with-the-fingertips-on-its-surface
  ;; a spoon lies 2 cm high on the island: the hands closing in on it may touch the island top
  ;; (the grasp's container links); a bottle standing there may not be grasped through it
  (btw-tut:init-projection)
  (flet ((spawn (name type x)
           (btr:add-object btr:*current-bullet-world* :mesh name
                           (cl-transforms:make-pose (cl-transforms:make-3d-vector x 1.75 0.9)
                                                    (cl-transforms:make-identity-rotation))
                           :mesh type :mass 0.1 :types (list type))))
    (spawn :flat-spoon :spoon -1.2)
    (spawn :standing-bottle :bottle -0.9))
  (btr:simulate btr:*current-bullet-world* 100)
  (is (< (- (bottom-z :flat-spoon) (link-top "kitchen_island_surface")) 0.01)
      "the spoon came to rest on the island")
  (is (equal '("kitchen_island_surface") (pp-plans::container-links :flat-spoon)))
  (is (null (pp-plans::container-links :standing-bottle)))
  (btr:add-object btr:*current-bullet-world* :mesh :floating-spoon
                  (cl-transforms:make-pose (cl-transforms:make-3d-vector -1.5 1.75 1.2)
                                           (cl-transforms:make-identity-rotation))
                  :mesh :spoon :mass 0.1 :types '(:spoon))
  (is (null (pp-plans::container-links :floating-spoon)) "a spoon in the air rests on nothing"))
