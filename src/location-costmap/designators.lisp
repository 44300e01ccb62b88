;;;; Location designators resolved through costmaps: the DESIG-COSTMAP predicate, the
;;;; VISIBLE-FOR, REACHABLE-FOR, REACHABLE-FROM and ON costmaps, the costmap location generator and validators.

(in-package :cram-location-costmap)

(defparameter *visibility-gauss-share* 0.5d0
  "Standard deviation of the VISIBLE-FOR gaussian as a share of VISIBILITY-COSTMAP-SIZE.")

(defparameter *reach-gauss-share* 0.5d0
  "Standard deviation of the REACHABLE-FOR gaussian as a share of COSTMAP-IN-REACH-DISTANCE.")

(defparameter *surface-margin* 0.05d0
  "Distance (metres) ON samples keep from the edges of a surface when no object is given.")

(defparameter *line-of-sight-stride* 2
  "VISIBLE-FOR costmaps cast one ray per block of this many cells squared.")

(defun diagonal-covariance (sigma)
  (let ((v (* sigma sigma))) (list (list v 0) (list 0 v))))

(defun metadata (predicate &optional (default nil default-p))
  (if default-p
      (costmap-metadata-value predicate :default default)
      (costmap-metadata-value predicate)))

(defun add-occupancy (costmap padding)
  (register-cost-function
   costmap
   (make-occupancy-grid-cost-function
    (environment-occupancy-grid :padding padding :width (width costmap) :height (height costmap)
                                :origin-x (origin-x costmap) :origin-y (origin-y costmap)
                                :resolution (resolution costmap)))
   'occupancy 1))

(defparameter *robot-parking-pose*
  (cl-transforms:make-pose (cl-transforms:make-3d-vector 1000 1000 -1000)
                           (cl-transforms:make-identity-rotation))
  "Where the robot waits in a scratch world while rays are cast: far from everything.")

(defvar *scratch-worlds* (make-hash-table :test 'eq :weakness :key :synchronized t)
  "Location designator -> alist robot name -> its scratch world.")

(defun park-robot (world robot-name)
  "Move the robot ROBOT-NAME of WORLD to *ROBOT-PARKING-POSE*."
  (let ((robot (robot-world-object robot-name world)))
    (when robot (setf (btr:pose robot) *robot-parking-pose*))
    world))

(defun designator-scratch-world (designator robot-name)
  "A copy of the belief state for DESIGNATOR's checks, made once per designator and robot: the
robot ROBOT-NAME waits far away, so that rays are cast without it and candidate base poses are
tested by moving it there and back."
  (let ((entry (assoc robot-name (gethash designator *scratch-worlds*))))
    (if entry
        (cdr entry)
        (let ((world (park-robot (btr:copy-world) robot-name)))
          (push (cons robot-name world) (gethash designator *scratch-worlds*))
          world))))

(defun register-ring-costs (costmap target outer inner padding gauss-share names)
  "Register on COSTMAP the costs of a base pose near TARGET: within OUTER of it, in free space
\(PADDING), not nearer than INNER, and a gaussian around it of OUTER × GAUSS-SHARE. NAMES: the
names of the range, minimal range and gaussian cost functions."
  (destructuring-bind (range-name minimal-name gauss-name) names
    (register-cost-function costmap (make-range-cost-function target outer) range-name 0)
    (add-occupancy costmap padding)
    (register-cost-function costmap (make-range-cost-function target inner :invert t) minimal-name 2)
    (register-cost-function costmap (make-gauss-cost-function
                                     target (diagonal-covariance (* outer gauss-share)))
                            gauss-name 3)))

(defun visible-for-costmap (designator robot)
  "The costmap of the base poses from which the robot ROBOT sees the target of DESIGNATOR:
free space (COSTMAP-PADDING) within VISIBILITY-COSTMAP-SIZE of the target, a gaussian around
it, and a line of sight from the camera height; the base faces the target."
  (let ((robot (designator-robot-name robot)))
    (with-robot (robot)
      (multiple-value-bind (target object) (designator-target designator)
        (let* ((costmap (make-location-costmap))
               (radius (metadata 'visibility-costmap-size))
               (padding (metadata 'costmap-padding))
               (samples (metadata 'orientation-samples 1))
               (step (metadata 'orientation-sample-step (/ pi 18))))
          (register-ring-costs costmap target radius padding padding *visibility-gauss-share*
                               '(visibility-range visibility-minimal-range visibility-gauss))
          (register-cost-function costmap
                                  (make-line-of-sight-cost-function
                                   target (robot-camera-height robot)
                                   :target-object object :stride *line-of-sight-stride*
                                   ;; the points the visibility validator checks
                                   :points (view-target-points target object)
                                   :world (designator-scratch-world designator robot))
                                  'line-of-sight 20)
          (register-orientation-generator costmap (make-angle-to-point-generator
                                                   target :samples samples :sample-step step))
          (register-height-generator costmap (make-constant-height-function 0))
          costmap)))))

(defun reachable-for-costmap (designator robot)
  "The costmap of the base poses from which the robot ROBOT reaches the target of DESIGNATOR:
free space (COSTMAP-MANIPULATION-PADDING), between COSTMAP-REACH-MINIMAL-DISTANCE and
COSTMAP-IN-REACH-DISTANCE from the target, a gaussian around it; the base faces the target,
turned so that the shoulder of the ARM (when given) faces it."
  (let ((robot (designator-robot-name robot)))
    (with-robot (robot)
      (multiple-value-bind (target) (designator-target designator)
        (let* ((costmap (make-location-costmap))
               (reach (metadata 'costmap-in-reach-distance))
               (minimal (metadata 'costmap-reach-minimal-distance 0))
               (padding (metadata 'costmap-manipulation-padding (metadata 'costmap-padding)))
               (samples (metadata 'orientation-samples 1))
               (step (metadata 'orientation-sample-step (/ pi 18)))
               (arm (desig:desig-prop-value designator :arm))
               (lateral (if arm (arm-lateral-offset robot arm) 0d0)))
          (multiple-value-bind (tx ty) (point-xy target "REACHABLE-FOR target")
            (register-ring-costs costmap target reach minimal padding *reach-gauss-share*
                                 '(reach-range reach-minimal-range reach-gauss))
            (register-orientation-generator
             costmap
             (make-orientation-generator
              (lambda (x y)
                (let ((d (sqrt (+ (expt (- tx x) 2) (expt (- ty y) 2)))))
                  (- (atan (- ty y) (- tx x))
                     (if (> d (abs lateral)) (asin (/ lateral d)) 0d0))))
              :samples samples :sample-step step))
            (register-height-generator costmap (make-constant-height-function 0))
            costmap))))))

(defun reachable-from-costmap (designator from)
  "The costmap of (reachable-from FROM): places within COSTMAP-IN-REACH-DISTANCE (horizontally)
of FROM, the nearer the likelier (a gaussian around it). FROM is a robot's name (the robot's
base pose in the belief state) or a pose or pose-stamped of the base of the robot in the
belief state."
  (let* ((robot-object (btr:get-robot-object))
         (robot (cond ((and (symbolp from) from) (designator-robot-name from))
                      (robot-object (designator-robot-name (btr:name robot-object)))
                      (t (error "Location designator ~a: (reachable-from ~s) needs a robot in ~
                                 the belief state." designator from))))
         (base (cond ((symbolp from)
                      (let ((o (robot-world-object robot)))
                        (unless o
                          (error "Location designator ~a: (reachable-from ~s): that robot is not ~
                                  in the belief state." designator from))
                        (btr:pose o)))
                     ((or (typep from 'cl-transforms-stamped:pose-stamped)
                          (typep from 'cl-transforms:pose))
                      (pose-in-map from "REACHABLE-FROM pose"))
                     (t (error "Location designator ~a: (reachable-from ~s), expected a robot ~
                                name or a pose." designator from)))))
    (with-robot (robot)
      (let ((costmap (make-location-costmap))
            (reach (metadata 'costmap-in-reach-distance)))
        (register-cost-function costmap (make-range-cost-function (cl-transforms:origin base) reach)
                                'reachable-from-space 5)
        (register-cost-function costmap (make-gauss-cost-function
                                         (cl-transforms:origin base)
                                         (diagonal-covariance (* reach *reach-gauss-share*)))
                                'reachable-from-weighted 4)
        (let ((yaw (held-object-yaw-from designator base)))
          (when yaw
            (register-orientation-ordering costmap (make-preferred-yaw-ordering yaw))))
        costmap))))

(defun held-item (designator key)
  "The object of the belief state that the value of KEY in DESIGNATOR (an object designator)
stands for, when the robot holds it; else NIL."
  (let* ((object (desig:desig-prop-value designator key))
         (item (and (typep object 'desig:object-designator)
                    (object-designator-world-object object))))
    (and (held-by-robot-p item) item)))

(defun held-object-yaw-from (designator base)
  "When the FOR object of DESIGNATOR is held by the robot: the yaw (map) it has when the robot,
standing at BASE (a map pose), turns it no more than it is turned in hand now, else NIL. Its
places come in that orientation first (an object held by its side goes down from where the
robot stands without turning the wrist)."
  (let ((item (for-object designator)))
    (when (held-by-robot-p item)
      (+ (cl-transforms:get-yaw (cl-transforms:orientation base))
         (- (cl-transforms:get-yaw (cl-transforms:orientation (btr:pose item)))
            (cl-transforms:get-yaw (cl-transforms:orientation (btr:pose (btr:get-robot-object)))))))))

(defun supporting-items (x-min y-min x-max y-max top exclude &optional (world btr:*current-bullet-world*))
  "Bounding rectangles (x0 y0 x1 y1) of the items standing on the surface, except EXCLUDE."
  (loop for o in (btr:objects world)
        when (and (typep o 'btr:item) (not (eq o exclude)))
          append (multiple-value-bind (lo hi) (btr:aabb o)
                   (when (and (< (abs (- (cl-transforms:z lo) top)) 0.05d0)
                              (< (cl-transforms:x lo) x-max) (> (cl-transforms:x hi) x-min)
                              (< (cl-transforms:y lo) y-max) (> (cl-transforms:y hi) y-min))
                     (list (list (cl-transforms:x lo) (cl-transforms:y lo)
                                 (cl-transforms:x hi) (cl-transforms:y hi)))))))

(defun items-free-space-function (items margin)
  "A cost function: 0 within MARGIN metres of the rectangles ITEMS ((x0 y0 x1 y1) ...), else 1.
With double-float numbers, it fills a costmap's grid without a call per cell."
  (let ((function (lambda (x y)
                    (if (loop for (a b c d) in items
                              thereis (and (< (- a margin) x (+ c margin))
                                           (< (- b margin) y (+ d margin))))
                        0d0 1d0))))
    (if (and (typep margin 'double-float)
             (every (lambda (item) (and (alexandria:proper-list-p item) (= (length item) 4)
                                        (every (lambda (v) (typep v 'double-float)) item)))
                    items))
        ;; the grown rectangles as the function computes them, x0 y0 x1 y1 each
        (let ((grown (make-array (* 4 (length items)) :element-type 'double-float)))
          (loop for (a b c d) in items
                for i from 0 by 4
                do (setf (aref grown i) (- a margin) (aref grown (+ i 1)) (- b margin)
                         (aref grown (+ i 2)) (+ c margin) (aref grown (+ i 3)) (+ d margin)))
          (make-cost-function
           function
           :name 'items-free-space
           :grid-evaluator
           (cell-evaluator (x y)
             (if (loop for i of-type fixnum from 0 below (length grown) by 4
                       thereis (and (< (aref grown i) x (aref grown (+ i 2)))
                                    (< (aref grown (+ i 1)) y (aref grown (+ i 3)))))
                 0d0 1d0))))
        function)))

(defun turned-items-free-space-function (items half-x half-y yaw-function)
  "A cost function: 0 where an object of half extents HALF-X, HALF-Y (in its own frame), turned
to the yaw YAW-FUNCTION gives for the place (x y), would overlap one of the rectangles ITEMS
\((x0 y0 x1 y1) ...); else 1. A long, thin object (a spoon) laid along a table's edge needs its
length only along it."
  (lambda (x y)
    (let* ((yaw (funcall yaw-function x y))
           (c (abs (cos yaw))) (s (abs (sin yaw)))
           (ex (+ (* c half-x) (* s half-y))) (ey (+ (* s half-x) (* c half-y))))
      (if (loop for (a b c1 d) in items
                thereis (and (< (- a ex) x (+ c1 ex)) (< (- b ey) y (+ d ey))))
          0d0 1d0))))

(defun object-half-extents (object)
  "(values half-x half-y) of the belief-state OBJECT in its own frame, from its origin (the
larger side of its box, BTR:LOCAL-AABB, on each axis)."
  (multiple-value-bind (lo hi) (btr:local-aabb object)
    (values (max (abs (cl-transforms:x lo)) (abs (cl-transforms:x hi)))
            (max (abs (cl-transforms:y lo)) (abs (cl-transforms:y hi))))))

(defun object-footprint (object)
  "(values half-size lift) of the belief-state OBJECT as it is put down, upright: half the
larger of its horizontal extents, from its box in its own frame (BTR:LOCAL-AABB), so the same
however it is held now; and the height of its origin above the surface, which is the larger of
its origin's height above its bottom standing upright and (as CRAM's height generator takes
it) above the bottom of its box in the map as it is now. The first keeps an object held turned
(a cup hanging on its side from a hand parked for carrying) from being put down into the
surface, which would throw it through; the second keeps the fingers holding a flat object
from below (the spoon) clear of the surface."
  (multiple-value-bind (lo hi) (btr:local-aabb object)
    (values (* 0.5d0 (max (- (cl-transforms:x hi) (cl-transforms:x lo))
                          (- (cl-transforms:y hi) (cl-transforms:y lo))))
            (max (- (cl-transforms:z lo))
                 (- (cl-transforms:z (cl-transforms:origin (btr:pose object)))
                    (cl-transforms:z (btr:aabb object)))))))

(defun on-costmap (designator surface)
  "The costmap of the poses on the SURFACE object designator: its top rectangle shrunk by a
margin (half the size of the FOR object, when given), away from the items already there; the
height is the surface top, plus the FOR object's height of its origin above its bottom. Poses
for a FOR object come in four orientations, quarter turns about the vertical (the first
unturned), so that an object held by its side can be put down from where the robot stands."
  (let ((for-object (for-object designator)))
    (multiple-value-bind (x0 y0 x1 y1 top env link) (surface-of surface)
      (multiple-value-bind (margin lift)
          (if for-object (object-footprint for-object) (values *surface-margin* 0d0))
      (let* ((costmap (make-location-costmap))
             (cx (/ (+ x0 x1) 2)) (cy (/ (+ y0 y1) 2))
             (items (supporting-items x0 y0 x1 y1 top for-object)))
        (register-cost-function costmap
                                (if link
                                    (link-top-function env link margin)
                                    (make-rectangle-cost-function
                                     (min cx (+ x0 margin)) (min cy (+ y0 margin))
                                     (max cx (- x1 margin)) (max cy (- y1 margin))))
                                'on-surface 0)
        (when items
          (register-cost-function costmap (items-free-space-function items margin)
                                  'on-free-space 5))
        (register-height-generator costmap (make-constant-height-function (+ top lift)))
        (register-orientation-generator costmap (if for-object
                                                    (make-quarter-turns-orientation-generator)
                                                    (make-identity-orientation-generator)))
        costmap)))))

;;; ---- the Prolog interface ------------------------------------------------------------------------

(def-fact-group location-costmap-predicates (desig-costmap)
  (<- (desig-costmap ?designator ?costmap)
    (desig:loc-desig? ?designator)
    (desig:desig-prop ?designator (:visible-for ?robot))
    (lisp-fun visible-for-costmap ?designator ?robot ?costmap))
  (<- (desig-costmap ?designator ?costmap)
    (desig:loc-desig? ?designator)
    (desig:desig-prop ?designator (:reachable-for ?robot))
    (lisp-fun reachable-for-costmap ?designator ?robot ?costmap))
  (<- (desig-costmap ?designator ?costmap)
    (desig:loc-desig? ?designator)
    (desig:desig-prop ?designator (:on ?surface))
    (lisp-fun on-costmap ?designator ?surface ?costmap))
  (<- (desig-costmap ?designator ?costmap)
    (desig:loc-desig? ?designator)
    (desig:desig-prop ?designator (:reachable-from ?from))
    (lisp-fun reachable-from-costmap ?designator ?from ?costmap))

  (<- (costmap ?costmap)
    (-> (bound ?costmap)
        (lisp-type ?costmap location-costmap)
        (lisp-fun make-location-costmap ?costmap)))
  (<- (costmap-add-function ?name ?function ?costmap)
    (lisp-fun register-cost-function ?costmap ?function ?name ?_))
  (<- (costmap-add-orientation-generator ?generator ?costmap)
    (lisp-fun register-orientation-generator ?costmap ?generator ?_))
  (<- (costmap-add-height-generator ?generator ?costmap)
    (lisp-fun register-height-generator ?costmap ?generator ?_))
  (<- (merged-desig-costmap ?designator ?costmap)
    (lisp-fun designator-costmap ?designator ?costmap)
    (lisp-pred identity ?costmap)))

(rob-int::define-predicate-documentation
  (desig-costmap "(desig-costmap ?designator ?costmap): a costmap for the location ?designator;
every solution contributes and they are merged.  Extendable: add rules that build a costmap with
(costmap ?cm) and (costmap-add-function ?name ?function ?cm).")
  (costmap "(costmap ?cm): ?cm is a location costmap; a new one when ?cm is unbound.")
  (costmap-add-function "(costmap-add-function ?name ?function ?cm): register a cost function.")
  (costmap-add-orientation-generator "(costmap-add-orientation-generator ?generator ?cm).")
  (costmap-add-height-generator "(costmap-add-height-generator ?generator ?cm).")
  (merged-desig-costmap "(merged-desig-costmap ?designator ?cm): all DESIG-COSTMAP solutions of
?designator merged into one costmap."))

(defvar *designator-costmaps* (make-hash-table :test 'eq :weakness :key :synchronized t)
  "Location designator -> its merged costmap (or :NONE).")

(defparameter *max-cached-costmaps* 128
  "How many designators' costmaps *DESIGNATOR-COSTMAPS* keeps: designators live on in task
trees and recorded runs, so the cache is emptied when it is full rather than when they go (a
costmap whose designator asks again is built again).")

(defun designator-costmap (designator)
  "The merged costmap of all DESIG-COSTMAP solutions of the location DESIGNATOR, or NIL when it
has none; computed once per designator.  A Lisp error while a costmap is built (an unknown
robot, object or link) is signalled, not turned into a failing goal."
  (let ((known (gethash designator *designator-costmaps*)))
    (cond ((eq known :none) nil)
          (known known)
          (t (let* ((costmaps (remove nil (mapcar (lambda (b) (cut:var-value '?costmap b))
                                                  (let ((*break-on-lisp-errors* t))
                                                    (cut:force-ll
                                                     (prolog '(desig-costmap ?designator ?costmap)
                                                             `((?designator . ,designator))))))))
                    (merged (and costmaps (merge-costmaps costmaps))))
               (when (>= (hash-table-count *designator-costmaps*) *max-cached-costmaps*)
                 (clrhash *designator-costmaps*))
               (setf (gethash designator *designator-costmaps*) (or merged :none))
               merged)))))

(defun forget-designator-costmap (designator)
  "Drop the cached costmap of the location DESIGNATOR (DESIGNATOR-COSTMAP), so that its memory
is freed before the cache would let it go: for designators made for one check only."
  (remhash designator *designator-costmaps*)
  designator)

(defun costmap-location-generator (designator)
  "Location generator: the infinite lazy list of pose-stamped samples (frame map) of the merged
costmap of DESIGNATOR, or no candidate when no DESIG-COSTMAP rule applies or the costmap is 0
everywhere."
  (let ((costmap (designator-costmap designator)))
    ;; the costmap visualization shows the costmap last sampled (BTR:CLEAR-COSTMAP-VIS-OBJECT)
    (when costmap (btr:add-costmap-function-object costmap))
    ;; a costmap that is 0 everywhere (nothing fits) has no candidates: the designator then
    ;; has no solution (a DESIGNATOR-ERROR, which plans retry), not a Lisp error
    (and costmap
         (handler-case (let ((samples (costmap-samples costmap)))
                         (cut:lazy-car samples)
                         samples)
           (invalid-probability-distribution () nil)))))

(desig:register-location-generator 20 costmap-location-generator
  "Samples of the location costmap of the designator (DESIG-COSTMAP).")

;;; ---- validators ------------------------------------------------------------------------------------

(defstruct (robot-pose-request (:conc-name request-))
  robot target object kind scratch-world)

(defvar *designator-requests* (make-hash-table :test 'eq :weakness :key :synchronized t)
  "Location designator -> list of ROBOT-POSE-REQUESTs for its validators.")

(defun designator-requests (designator)
  (multiple-value-bind (known found) (gethash designator *designator-requests*)
    (if found
        known
        (setf (gethash designator *designator-requests*)
              (loop for (key kind) in '((:visible-for :visible) (:reachable-for :reachable))
                    for robot = (desig:desig-prop-value designator key)
                    when robot
                      collect (let ((name (designator-robot-name robot)))
                                (multiple-value-bind (target object) (designator-target designator)
                                  (make-robot-pose-request
                                   :robot name :target target :object object :kind kind
                                   :scratch-world (designator-scratch-world designator name)))))))))

(defun candidate-pose (solution)
  (typecase solution
    (cl-transforms-stamped:pose-stamped
     (and (map-frame-p (cl-transforms-stamped:frame-id solution))
          (cl-transforms-stamped:pose-stamped->pose solution)))
    (cl-transforms:pose solution)))

(defun horizontal-distance (pose point)
  (let ((o (cl-transforms:origin pose)))
    (sqrt (+ (expt (- (cl-transforms:x o) (cl-transforms:x point)) 2)
             (expt (- (cl-transforms:y o) (cl-transforms:y point)) 2)))))

(defun robot-pose-distance-validator (designator solution)
  "Location validator: rejects VISIBLE-FOR poses farther than VISIBILITY-COSTMAP-SIZE from the
target and REACHABLE-FOR poses outside the reach ring."
  (let ((requests (and (typep designator 'desig:location-designator) (designator-requests designator)))
        (pose (candidate-pose solution)))
    (if (or (null requests) (null pose))
        :unknown
        (loop for r in requests
              for d = (horizontal-distance pose (request-target r))
              unless (with-robot ((request-robot r))
                       (ecase (request-kind r)
                         (:visible (<= d (+ (metadata 'visibility-costmap-size) 1d-6)))
                         (:reachable (<= (- (metadata 'costmap-reach-minimal-distance 0) 1d-6)
                                         d (+ (metadata 'costmap-in-reach-distance) 1d-6)))))
                return :reject
              finally (return :unknown)))))

(defun robot-pose-visibility-validator (designator solution)
  "Location validator: rejects VISIBLE-FOR poses from which a ray at the robot's camera height
does not reach the target (for an object: its centre, top and sides)."
  (let ((requests (and (typep designator 'desig:location-designator) (designator-requests designator)))
        (pose (candidate-pose solution)))
    (if (or (null requests) (null pose))
        :unknown
        (loop for r in requests
              when (eq (request-kind r) :visible)
                do (let* ((o (cl-transforms:origin pose))
                          (eye (cl-transforms:make-3d-vector
                                (cl-transforms:x o) (cl-transforms:y o)
                                (robot-camera-height (request-robot r)))))
                     (unless (line-of-sight-p eye (view-target-points (request-target r) (request-object r))
                                              (request-object r)
                                              :world (request-scratch-world r))
                       (return :reject)))
              finally (return :unknown)))))

(defun robot-pose-collision-validator (designator solution)
  "Location validator: rejects VISIBLE-FOR and REACHABLE-FOR base poses at which the robot,
placed there in a copy of the belief state, touches anything but the floor and what it holds."
  (let ((requests (and (typep designator 'desig:location-designator) (designator-requests designator)))
        (pose (candidate-pose solution)))
    (cond ((or (null requests) (null pose)) :unknown)
          ((loop for r in requests
                 for world = (request-scratch-world r)
                 for robot = (robot-world-object (request-robot r) world)
                 thereis (and robot
                              (unwind-protect
                                   (robot-pose-collisions (btr:name robot) pose :world world
                                                                               :in-place t)
                                (park-robot world (request-robot r)))))
           :reject)
          (t :unknown))))

(desig:register-location-validation-function 30 robot-pose-distance-validator
  "VISIBLE-FOR / REACHABLE-FOR: distance of the base from the target.")
(desig:register-location-validation-function 35 robot-pose-visibility-validator
  "VISIBLE-FOR: line of sight from the camera height to the target.")
(desig:register-location-validation-function 40 robot-pose-collision-validator
  "VISIBLE-FOR / REACHABLE-FOR: the robot at the pose collides with nothing.")
