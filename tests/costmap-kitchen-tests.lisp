;;;; Location designators in the IAI kitchen with a PR2 and a mug on the kitchen island.

(in-package :cram-costmap-tests)

(in-suite costmap)

(defparameter *mug-start* '((-0.9 0.6 0.903) (0 0 0 1))
  "Where the mug is spawned: on the kitchen island, its bottom on the surface top (0.851).")

(defvar *kitchen-world* nil "The kitchen world the tests share, built once.")

(defun main-file (relative)
  (asdf:system-relative-pathname "cram-plans/cram-location-costmap" relative))

(defun build-kitchen-world ()
  (btr:register-ros-package "cram_plans_resources" (namestring (main-file "resources/")))
  (btr:add-objects-to-mesh-list "cram_plans_resources" :directory "meshes")
  (let ((btr:*current-bullet-world* (make-instance 'btr:bt-reasoning-world))
        (kitchen (uiop:read-file-string (main-file "resources/iai_kitchen.urdf")))
        (pr2 (uiop:read-file-string (main-file "robots/pr2/pr2.urdf"))))
    (cut:force-ll
     (prolog:prolog
      `(and (btr:bullet-world ?w)
            (assert (btr:object ?w :static-plane :floor ((0 0 0) (0 0 0 1)) :normal (0 0 1)
                                :constant 0))
            (assert (btr:object ?w :urdf :iai-kitchen ((0 0 0) (0 0 0 1)) :urdf ,kitchen
                                :collision-group :static-filter
                                :collision-mask (:default-filter :character-filter)))
            (assert (btr:object ?w :urdf :pr2 ((0 0 0) (0 0 0 1)) :urdf ,pr2))
            (-> (rob-int:robot-joint-states :pr2 :arm :left :park ?left)
                (assert (btr:joint-state ?w :pr2 ?left))
                (true))
            (-> (rob-int:robot-joint-states :pr2 :arm :right :park ?right)
                (assert (btr:joint-state ?w :pr2 ?right))
                (true))
            (assert (btr:object ?w :mesh mug-1 ,*mug-start* :mass 0.2 :color (0.8 0.3 0.1)
                                :mesh :mug)))))
    (btr:simulate btr:*current-bullet-world* 1)
    btr:*current-bullet-world*))

(defmacro in-kitchen (&body body)
  "Run BODY in a copy of the shared kitchen world, with the PR2 as the current robot."
  `(progn
     (unless *kitchen-world*
       (let ((rob-int:*robot-name* :pr2)) (setf *kitchen-world* (build-kitchen-world))))
     (let ((rob-int:*robot-name* :pr2)
           (btr:*current-bullet-world* *kitchen-world*))
       (btr:with-copied-world ()
         ,@body))))

(defun turn-about-z (object yaw)
  "Put OBJECT at the origin, turned by YAW radians about the vertical."
  (setf (btr:pose object)
        (cl-transforms:make-pose (cl-transforms:make-3d-vector 0 0 0)
                                 (cl-transforms:axis-angle->quaternion
                                  (cl-transforms:make-3d-vector 0 0 1) yaw))))

(defun mug-designator ()
  (desig:an object (type mug) (name mug-1)))

(defun visible-for-mug ()
  (desig:a location (visible-for pr2) (object (desig:an object (type mug) (name mug-1)))))

(defun reachable-for-mug ()
  (desig:a location (reachable-for pr2) (object (desig:an object (type mug) (name mug-1)))))

(defun robot () (btr:object btr:*current-bullet-world* :pr2))

(defun point-head-at (point)
  "Turn the PR2's head so that its camera looks at POINT."
  (let ((robot (robot)))
    (dotimes (i 4)
      (let* ((base (btr:pose robot))
             (to-base (cl-transforms:transform-inv (cl-transforms:pose->transform base)))
             (camera (cl-transforms:transform-point to-base (cl-transforms:origin (btr:camera-pose :pr2))))
             (target (cl-transforms:transform-point to-base point))
             (d (cl-transforms:v- target camera))
             (pan-error (atan (cl-transforms:y d) (cl-transforms:x d)))
             (pan (+ (btr:joint-state robot "head_pan_joint")
                     (- pan-error (cl-transforms:get-yaw
                                   (cl-transforms:orientation
                                    (cl-transforms:transform-pose
                                     to-base (btr:link-pose robot "head_pan_link")))))))
             (tilt (atan (- (cl-transforms:z d))
                         (sqrt (+ (expt (cl-transforms:x d) 2) (expt (cl-transforms:y d) 2))))))
        (btr:set-robot-state-from-joints `(("head_pan_joint" ,pan) ("head_tilt_joint" ,tilt)) robot)))))

(defun mug-visible-from (pose)
  "Place the robot at POSE, point its head at the mug and ask BTR:VISIBLE."
  (setf (btr:pose (robot)) (cl-transforms-stamped:pose-stamped->pose pose))
  (point-head-at (costmap::object-center (btr:object btr:*current-bullet-world* 'mug-1)))
  (not (null (prolog:prolog `(and (btr:bullet-world ?w) (btr:visible ?w :pr2 mug-1))))))

;;; ---- the world -------------------------------------------------------------------------------------

(test mug-rests-on-the-island
  (in-kitchen
    (let ((p (cl-transforms:origin (btr:pose (btr:object btr:*current-bullet-world* 'mug-1)))))
      (is (< (abs (- (cl-transforms:x p) -0.9)) 0.03))
      (is (< (abs (- (cl-transforms:y p) 0.6)) 0.03))
      (is (< (abs (- (cl-transforms:z p) 0.9)) 0.01))
      (is (equal '(:iai-kitchen) (btr:find-objects-in-contact btr:*current-bullet-world* 'mug-1)))
      (is (btr:stable-p btr:*current-bullet-world* 'mug-1)))))

(test environment-occupancy
  (in-kitchen
    (let ((free (costmap:environment-occupancy-grid))
          (padded (costmap:environment-occupancy-grid :padding 0.3)))
      (is (costmap:occupied-p free -1.0 1.5) "the kitchen island occupies its footprint")
      (is (not (costmap:occupied-p free 0 0)) "the middle of the kitchen is free")
      (is (not (costmap:occupied-p free -0.45 1.5)))
      (is (costmap:occupied-p padded -0.45 1.5) "the padding grows the island by 0.3 m")
      (is (not (costmap:occupied-p padded -0.25 1.5)))
      (is (eq padded (costmap:environment-occupancy-grid :padding 0.3)) "grids are cached")
      (btr:set-robot-state-from-joints '(("kitchen_island_left_upper_drawer_main_joint" 0.4))
                                       (btr:object btr:*current-bullet-world* :iai-kitchen))
      (let ((opened (costmap:environment-occupancy-grid :padding 0.3)))
        (is (not (eq padded opened)) "a new joint state gives a new grid")
        (is (costmap:occupied-p opened -0.25 0.9) "the open drawer occupies the floor in front")))))

(test a-long-object-is-kept-clear-of-items-by-its-extents-as-it-will-lie
  ;; a spoon-like object (0.11 long from its origin, 0.023 wide) next to an item (a 10 cm
  ;; square at the origin): 6 cm beside the item it fits when it lies along the item's side,
  ;; not when it lies pointing at the item
  (let ((items '((-0.05d0 -0.05d0 0.05d0 0.05d0))))
    (flet ((free-p (yaw x y)
             (> (funcall (costmap::turned-items-free-space-function
                          items 0.11d0 0.023d0 (lambda (x y) (declare (ignore x y)) yaw))
                         x y)
                0)))
      (is-true (free-p (/ pi 2) 0.08d0 0d0) "lying along the item's side")
      (is (not (free-p 0d0 0.08d0 0d0)) "pointing at the item")
      (is-true (free-p 0d0 0.17d0 0d0) "pointing at it, 17 cm away")
      (is (not (free-p (/ pi 2) 0d0 0.08d0)) "turned a quarter, on the other axis"))))

(test a-turned-link-occupies-its-own-outline
  ;; the kitchen turned by 0.4 rad: the island occupies its turned outline, not the larger box
  ;; around it in the map (whose corners lie on free floor)
  (in-kitchen
    (let* ((kitchen (btr:object btr:*current-bullet-world* :iai-kitchen))
           (name "kitchen_island_surface"))
      (turn-about-z kitchen 0.4d0)
      (let* ((index (position name (btr:link-names kitchen) :test #'string=))
             (grid (costmap:environment-occupancy-grid))
             (corners (costmap::link-footprint kitchen index name)))
        (multiple-value-bind (lo hi) (btr:aabb kitchen index)
          (let ((cx (/ (+ (cl-transforms:x lo) (cl-transforms:x hi)) 2))
                (cy (/ (+ (cl-transforms:y lo) (cl-transforms:y hi)) 2)))
            (is (= 4 (length corners)) "a box's outline has 4 corners: ~a" corners)
            (is (costmap:occupied-p grid cx cy) "the island's middle is occupied")
            ;; two corners of the map box, 5 cm in: outside the turned island
            (is (not (costmap:occupied-p grid (+ (cl-transforms:x lo) 0.05) (+ (cl-transforms:y lo) 0.05))))
            (is (not (costmap:occupied-p grid (- (cl-transforms:x hi) 0.05) (- (cl-transforms:y hi) 0.05))))))))))

(test places-on-a-turned-surface-lie-on-it
  ;; the kitchen turned by 0.4 rad: (on island) places lie on the island's turned top, shrunk
  ;; by the margin, not in the corners of the larger box around it in the map
  (in-kitchen
    (let* ((kitchen (btr:object btr:*current-bullet-world* :iai-kitchen))
           (name "kitchen_island_surface")
           (index (position name (btr:link-names kitchen) :test #'string=))
           (straight (costmap::link-top-function kitchen name 0.05d0)))
      (let ((lo (btr:aabb kitchen index)))
        (is (= 1 (funcall straight (+ (cl-transforms:x lo) 0.06) (+ (cl-transforms:y lo) 0.06)))
            "unturned: the box in the map, shrunk by the margin")
        (is (= 0 (funcall straight (+ (cl-transforms:x lo) 0.04) (+ (cl-transforms:y lo) 0.06)))))
      (turn-about-z kitchen 0.4d0)
      (let ((top (costmap::link-top-function kitchen name 0.05d0))
            (centre (cl-transforms:origin (btr:link-pose kitchen name))))
        (multiple-value-bind (lo hi) (btr:aabb kitchen index)
          (is (= 1 (funcall top (cl-transforms:x centre) (cl-transforms:y centre))))
          (is (= 0 (funcall top (+ (cl-transforms:x lo) 0.06) (+ (cl-transforms:y lo) 0.06))))
          (is (= 0 (funcall top (- (cl-transforms:x hi) 0.06) (- (cl-transforms:y hi) 0.06)))))
        ;; every sample of an ON designator lies on the turned top
        (let* ((?surface (desig:an object (type counter-top) (urdf-name kitchen-island-surface)
                                   (part-of iai-kitchen)))
               (costmap (costmap:designator-costmap (desig:a location (on ?surface)))))
          (is (every (lambda (point)
                       (= 1 (funcall top (cl-transforms:x point) (cl-transforms:y point))))
                     (loop repeat 50 collect (costmap:gen-costmap-sample-point costmap)))))))))

;;; ---- visible-for -----------------------------------------------------------------------------------

(test visible-for-mug-over-20-seeds
  (in-kitchen
    (let ((visible 0) (poses '()))
      (dotimes (seed 20)
        (costmap:seed-costmaps seed)
        (let ((pose (desig:reference (visible-for-mug))))
          (push pose poses)
          (is (equal "map" (cl-transforms-stamped:frame-id pose)))
          (is (<= (costmap::horizontal-distance pose (costmap::object-center
                                                      (btr:object btr:*current-bullet-world* 'mug-1)))
                  2.0))
          (is (null (costmap:robot-pose-collisions :pr2 pose)))
          (when (mug-visible-from pose) (incf visible))))
      (is (>= visible 19) "the mug was visible from ~d of 20 poses" visible)
      (is (= 20 (length (remove-duplicates (mapcar #'pose-xy poses) :test #'equal)))))))

(test visible-for-faces-the-target
  (in-kitchen
    (costmap:seed-costmaps 7)
    (let* ((pose (desig:reference (visible-for-mug)))
           (mug (costmap::object-center (btr:object btr:*current-bullet-world* 'mug-1)))
           (o (cl-transforms:origin pose)))
      (is (< (angle-difference (yaw-of pose) (atan (- (cl-transforms:y mug) (cl-transforms:y o))
                                                   (- (cl-transforms:x mug) (cl-transforms:x o))))
             1d-6)))))

(test visible-for-location-of-a-pose
  (in-kitchen
    (costmap:seed-costmaps 1)
    (let* ((?mug-pose (cl-transforms-stamped:pose->pose-stamped
                       "map" 0 (btr:pose (btr:object btr:*current-bullet-world* 'mug-1))))
           (?mug-location (desig:a location (pose ?mug-pose)))
           (pose (desig:reference (desig:a location (visible-for pr2) (location ?mug-location)))))
      (is (mug-visible-from pose)))))

(test visible-for-a-place-on-the-counter
  (in-kitchen
    (costmap:seed-costmaps 4)
    (let* ((?on-counter (desig:a location
                                 (on (desig:an object (type counter-top)
                                                      (urdf-name kitchen-island-surface)
                                                      (part-of iai-kitchen)))))
           (location-to-see (desig:a location (visible-for pr2) (location ?on-counter)))
           (spot (desig:reference ?on-counter))
           (pose (desig:reference location-to-see)))
      (is (<= (costmap::horizontal-distance pose (cl-transforms:origin spot)) 2.0))
      (is (null (costmap:robot-pose-collisions :pr2 pose)))
      (let ((o (cl-transforms:origin pose)))
        (is (costmap:line-of-sight-p (cl-transforms:make-3d-vector (cl-transforms:x o) (cl-transforms:y o)
                                                                    (costmap:robot-camera-height :pr2))
                                     (list (cl-transforms:origin spot)) nil
                                     :world (costmap::world-without '(:pr2))))))))

(test same-seed-same-pose
  (in-kitchen
    (flet ((pose-of (make seed)
             (costmap:seed-costmaps seed)
             (let ((p (desig:reference (funcall make))))
               (list (pose-xy p) (yaw-of p)))))
      (is (equal (pose-of #'visible-for-mug 9) (pose-of #'visible-for-mug 9)))
      (is (equal (pose-of #'reachable-for-mug 9) (pose-of #'reachable-for-mug 9)))
      (is (not (equal (pose-of #'visible-for-mug 9) (pose-of #'visible-for-mug 10)))))))

(test next-solutions-differ
  (in-kitchen
    (costmap:seed-costmaps 3)
    (let* ((d (visible-for-mug))
           (first (desig:reference d))
           (second (desig:reference (desig:next-solution d))))
      (is (not (equal (pose-xy first) (pose-xy second)))))))

;;; ---- reachable-for -----------------------------------------------------------------------------------

(test reachable-for-mug
  (in-kitchen
    (let ((reach (let ((rob-int:*robot-name* :pr2)) (costmap:costmap-metadata-value 'costmap:costmap-in-reach-distance)))
          (mug (costmap::object-center (btr:object btr:*current-bullet-world* 'mug-1))))
      (dotimes (seed 10)
        (costmap:seed-costmaps seed)
        (let ((pose (desig:reference (reachable-for-mug))))
          (is (<= 0.2 (costmap::horizontal-distance pose mug) reach))
          (is (null (costmap:robot-pose-collisions :pr2 pose)))
          (is (= 0 (cl-transforms:z (cl-transforms:origin pose)))))))))

(test reachable-for-with-arm-turns-the-shoulder-to-the-target
  (in-kitchen
    (costmap:seed-costmaps 2)
    (let* ((mug (costmap::object-center (btr:object btr:*current-bullet-world* 'mug-1)))
           (left (desig:reference (desig:a location (reachable-for pr2) (arm left)
                                           (object (desig:an object (name mug-1))))))
           (o (cl-transforms:origin left))
           (facing (atan (- (cl-transforms:y mug) (cl-transforms:y o)) (- (cl-transforms:x mug) (cl-transforms:x o)))))
      ;; the left shoulder is on the left, so the base turns right of the target direction
      (is (< (yaw-of left) (+ facing 1d-6)))
      (is (> (angle-difference (yaw-of left) facing) 0.05))
      (signals error (desig:reference (desig:a location (reachable-for pr2) (arm middle)
                                               (object (desig:an object (name mug-1)))))))))

;;; ---- on ------------------------------------------------------------------------------------------------

(test on-the-sink-area-surface
  (in-kitchen
    (costmap:seed-costmaps 6)
    (let ((d (desig:a location (on (desig:an object (type counter-top) (urdf-name sink-area-surface)
                                                    (part-of iai-kitchen))))))
      (loop for solution = d then (desig:next-solution solution)
            repeat 10
            for pose = (desig:reference solution)
            for o = (cl-transforms:origin pose)
            do (is (< 1.278 (cl-transforms:x o) 1.853))
               (is (< -0.275 (cl-transforms:y o) 1.325))
               (is (< (abs (- (cl-transforms:z o) 0.85)) 0.005))))))

(test on-for-an-object-lifts-it-by-its-origin-height
  (in-kitchen
    (costmap:seed-costmaps 6)
    (let* ((mug (btr:object btr:*current-bullet-world* 'mug-1))
           (lift (- (cl-transforms:z (cl-transforms:origin (btr:pose mug)))
                    (cl-transforms:z (nth-value 0 (btr:aabb mug)))))
           (pose (desig:reference (desig:a location (on (desig:an object (urdf-name sink-area-surface)
                                                                         (part-of iai-kitchen)))
                                           (for (desig:an object (name mug-1)))))))
      (is (< (abs (- (cl-transforms:z (cl-transforms:origin pose)) (+ 0.85 lift))) 0.005)))))

(test a-for-object-missing-by-name-is-sized-by-its-type
  ;; CRAM's cleaning destinations name the FOR object some-name: the place is for an object of
  ;; its type, kept off the edges by such an object's footprint and lifted by its origin height
  (in-kitchen
    (btr:add-object btr:*current-bullet-world* :mesh 'bowl-1
                    (cl-transforms:make-pose (cl-transforms:make-3d-vector -0.9 1.0 0.9)
                                             (cl-transforms:make-identity-rotation))
                    :mesh :bowl :mass 0.2 :types '(:bowl))
    (flet ((region (for)
             (costmap:seed-costmaps 6)
             (let ((d (if for
                          (let ((?for for))
                            (desig:a location (on (desig:an object (urdf-name sink-area-surface)
                                                                   (part-of iai-kitchen)))
                                     (for ?for)))
                          (desig:a location (on (desig:an object (urdf-name sink-area-surface)
                                                                 (part-of iai-kitchen)))))))
               (let ((z (cl-transforms:z (cl-transforms:origin (desig:reference d))))
                     (c (costmap:designator-costmap d)))
                 (list (loop for x from 1.2d0 to 1.95d0 by 0.01d0
                             sum (loop for y from -0.35d0 to 1.4d0 by 0.01d0
                                       count (> (costmap:get-map-value c x y) 0)))
                       z)))))
      (destructuring-bind (plain plain-z) (region nil)
        (destructuring-bind (named named-z) (region (desig:an object (type bowl) (name bowl-1)))
          (destructuring-bind (missing missing-z) (region (desig:an object (type bowl) (name some-name)))
            (is (< named plain) "the bowl's footprint keeps places off the edges")
            (is (= named missing) "a missing name is sized as the bowl of its type")
            (is (> named-z plain-z) "lifted by the bowl's origin height")
            (is (< (abs (- named-z missing-z)) 1d-6))))
        ;; a type the belief state has no item of: the surface as it is
        (is (equal (list plain plain-z) (region (desig:an object (type cup) (name some-name)))))))))

(test a-for-object-missing-by-name-is-the-held-one-of-its-type
  ;; of two items of the type, the one the robot holds is the one a place is for
  (in-kitchen
    (flet ((bowl (name x)
             (btr:add-object btr:*current-bullet-world* :mesh name
                             (cl-transforms:make-pose (cl-transforms:make-3d-vector x 1.0 0.9)
                                                      (cl-transforms:make-identity-rotation))
                             :mesh :bowl :mass 0.2 :types '(:bowl))))
      (let ((lying (bowl 'bowl-1 -0.9)) (held (bowl 'bowl-2 -1.1))
            (place (desig:a location (for (desig:an object (type bowl) (name some-name))))))
        (is (eq lying (costmap::for-object place)) "none held: the first of its type")
        (btr:attach-object (btr:get-robot-object) held :link "l_gripper_palm_link")
        (is (eq held (costmap::for-object place)))
        (is (eq lying (costmap::for-object (desig:a location (for (desig:an object (name bowl-1))))))
            "an object the belief state has by its name is that one")
        (is (null (costmap::for-object (desig:a location (for (desig:an object (type cup) (name some-name)))))))))))

(test on-avoids-objects-already-there
  (in-kitchen
    (costmap:seed-costmaps 8)
    (let ((c (desig:a location (on (desig:an object (urdf-name kitchen-island-surface)
                                                    (part-of iai-kitchen))))))
      (desig:reference c)
      (is (= 0 (costmap:get-map-value (costmap:designator-costmap c) -0.9 0.6))))))

(test on-keeps-the-footprint-of-the-object-upright-however-it-is-held
  ;; the free space around the items already on a surface is the object's own footprint
  ;; upright, as it is put down: the same whether it now stands straight or hangs turned and
  ;; tipped in a hand (its box in the map is then larger)
  (in-kitchen
    (let* ((mug (btr:object btr:*current-bullet-world* 'mug-1))
           (upright (btr:pose mug)))
      (flet ((free-cells ()
               (let ((d (desig:a location (on (desig:an object (urdf-name kitchen-island-surface)
                                                              (part-of iai-kitchen)))
                                 (for (desig:an object (name mug-1))))))
                 (desig:reference d)
                 (let ((c (costmap:designator-costmap d)))
                   (loop for x from -1.5d0 to -0.3d0 by 0.02d0
                         sum (loop for y from 0.0d0 to 1.2d0 by 0.02d0
                                   count (> (costmap:get-map-value c x y) 0)))))))
        (let ((straight (free-cells)))
          (setf (btr:pose mug)
                (cl-transforms:make-pose
                 (cl-transforms:v+ (cl-transforms:origin upright) (cl-transforms:make-3d-vector 0 0 0.5))
                 (cl-transforms:q* (cl-transforms:axis-angle->quaternion
                                    (cl-transforms:make-3d-vector 0 0 1) (/ pi 4))
                                   (cl-transforms:axis-angle->quaternion
                                    (cl-transforms:make-3d-vector 1 0 0) 0.5d0))))
          (is (> straight 0))
          (is (= straight (free-cells))))))))

(test bad-designators-are-errors
  (in-kitchen
    (signals error (desig:reference (desig:a location (on (desig:an object (urdf-name no-such-surface)
                                                                           (part-of iai-kitchen))))))
    (signals error (desig:reference (desig:a location (on (desig:an object (urdf-name sink-area-surface)
                                                                           (part-of no-kitchen))))))
    (signals error (desig:reference (desig:a location (visible-for robby)
                                             (object (desig:an object (name mug-1))))))
    (signals error (desig:reference (desig:a location (visible-for pr2)
                                             (object (desig:an object (name no-such-mug))))))
    (signals error (desig:reference (desig:a location (reachable-for pr2))))))

;;; ---- Prolog integration and pictures --------------------------------------------------------------

(test desig-costmap-is-extendable
  (unwind-protect
       (progn
         (eval '(prolog:def-fact-group costmap-tests-custom (costmap:desig-costmap)
                 (prolog:<- (costmap:desig-costmap ?designator ?costmap)
                   (desig:desig-prop ?designator (:near-point (?x ?y)))
                   (costmap:costmap ?costmap)
                   (prolog:lisp-fun costmap:make-range-cost-function (?x ?y) 0.25 ?range)
                   (costmap:costmap-add-function near-point ?range ?costmap))))
         (in-kitchen
           (costmap:seed-costmaps 1)
           (let* ((?point '(0.5 -0.5))
                  (pose (desig:reference (desig:a location (near-point ?point)))))
             (is (<= (costmap::horizontal-distance pose (cl-transforms:make-3d-vector 0.5 -0.5 0))
                     0.27)))))
    (prolog:remove-fact-group 'costmap-tests-custom)))

(test heat-map-png
  (in-kitchen
    (costmap:seed-costmaps 1)
    (let* ((d (visible-for-mug))
           (path (merge-pathnames "cram-costmap-tests/visible-for.png" (uiop:temporary-directory))))
      (desig:reference d)
      (when (probe-file path) (delete-file path))
      (costmap:costmap-heat-map-png (costmap:designator-costmap d) path
                                    :occupancy-grid (costmap:environment-occupancy-grid :padding 0.3))
      (is (probe-file path))
      (with-open-file (s path :element-type '(unsigned-byte 8))
        (let ((header (make-array 8 :element-type '(unsigned-byte 8))))
          (read-sequence header s)
          (is (equalp #(137 80 78 71 13 10 26 10) header))
          (is (> (file-length s) 500)))))))
