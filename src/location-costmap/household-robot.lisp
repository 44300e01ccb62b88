;;;; Where the robot stands in the household: base poses around a container's handle for
;;;; (reachable-for R) (arm A) (object C), the restricted area of the kitchen, and the Prolog
;;;; rules of the household location designators.

(in-package :cram-location-costmap)

;;; ---- container parts ---------------------------------------------------------------------------

(defun container-designator-p (value)
  "True for an object designator naming a link of an environment (URDF-NAME)."
  (and (typep value 'desig:object-designator) (desig:desig-prop-value value :urdf-name) t))

(defun handle-link (env link)
  "The name of the handle of the part LINK of ENV (CL-URDF:HANDLE-LINK), or NIL."
  (let* ((l (urdf-link env link)) (handle (and l (cl-urdf:handle-link l))))
    (and handle (cl-urdf:name handle))))

(defun container-joint (env link)
  "The CL-URDF joint that moves the part LINK of ENV (CL-URDF:CONNECTING-JOINT), or NIL."
  (let ((l (urdf-link env link)))
    (and l (cl-urdf:connecting-joint l))))

(defun environment-part-target (designator)
  "(values point nil) for an object DESIGNATOR naming an environment link: the origin of its
handle, or the centre of the link's box when it has no handle."
  (multiple-value-bind (env link) (designator-link designator "Location designator")
    (let ((handle (handle-link env link)))
      (values (if handle
                  (cl-transforms:origin (btr:link-pose env handle))
                  (let ((body (link-body env link)))
                    (cl-transforms:v* (cl-transforms:v+ (body-lo body) (body-hi body)) 0.5d0)))
              nil))))

(defun joint-world-axis (env joint)
  "JOINT's axis in the map (the axis is given in the child link's frame)."
  (cl-transforms:rotate (cl-transforms:orientation (btr:link-pose env (cl-urdf:name (cl-urdf:child joint))))
                        (apply #'cl-transforms:make-3d-vector (cl-urdf:axis joint))))

(defun handle-positions-at-limits (env joint handle)
  "(values at-lower at-upper) of the HANDLE point (map) when JOINT is at its limits."
  (let* ((name (cl-urdf:name joint))
         (q (btr:joint-state env name))
         (axis (joint-world-axis env joint)))
    (multiple-value-bind (lower upper) (btr:joint-limits env name)
      (flet ((at (value)
               (if (eq (cl-urdf:joint-type joint) :prismatic)
                   (cl-transforms:v+ handle (cl-transforms:v* axis (- value q)))
                   (let ((hinge (cl-transforms:origin (btr:link-pose env (cl-urdf:name (cl-urdf:child joint))))))
                     (cl-transforms:v+ hinge
                                       (cl-transforms:rotate
                                        (cl-transforms:axis-angle->quaternion axis (- value q))
                                        (cl-transforms:v- handle hinge)))))))
        (values (at (or lower q)) (at (or upper q)))))))

(defun segment-distance (x y a b)
  "Horizontal distance of (X Y) from the segment A..B (3D points)."
  (let* ((ax (cl-transforms:x a)) (ay (cl-transforms:y a))
         (dx (- (cl-transforms:x b) ax)) (dy (- (cl-transforms:y b) ay))
         (len2 (+ (* dx dx) (* dy dy)))
         (k (if (< len2 1d-12) 0d0 (max 0d0 (min 1d0 (/ (+ (* (- x ax) dx) (* (- y ay) dy)) len2))))))
    (sqrt (+ (expt (- x ax (* k dx)) 2) (expt (- y ay (* k dy)) 2)))))

(defun container-reach-costmap (designator robot container)
  "Base poses for reaching CONTAINER's handle: for a drawer within reach of the handle
wherever the drawer is between closed and open, outside the drawer's sweep and on the side of
its axis that puts the ARM next to it; for a door within reach of the handle and clear of the
handle at both limits."
  (let ((robot (designator-robot-name robot)))
    (with-robot (robot)
      (multiple-value-bind (env link) (designator-link container "REACHABLE-FOR")
        (let* ((joint (or (container-joint env link)
                          (error "REACHABLE-FOR: ~s of ~s has no movable joint: it is no container."
                                 link (btr:name env))))
               (handle (environment-part-target container))
               (reach (metadata 'costmap-in-reach-distance))
               (minimal (max (metadata 'costmap-reach-minimal-distance 0) 0.3d0))
               (arm (keyword-of (desig:desig-prop-value designator :arm)))
               (costmap (make-location-costmap)))
          (multiple-value-bind (closed open) (handle-positions-at-limits env joint handle)
            (if (eq (cl-urdf:joint-type joint) :prismatic)
                (let* ((n (cl-transforms:v- open closed))
                       (nx (cl-transforms:x n)) (ny (cl-transforms:y n))
                       (nlen (max 1d-9 (sqrt (+ (* nx nx) (* ny ny)))))
                       (ux (/ nx nlen)) (uy (/ ny nlen))
                       ;; facing the furniture (-u), the robot's left is (uy, -ux)
                       (side (case arm (:left -1d0) (:right 1d0) (t 0d0))))
                  (register-cost-function
                   costmap
                   (lambda (x y)
                     (let* ((rx (- x (cl-transforms:x closed))) (ry (- y (cl-transforms:y closed)))
                            (d (segment-distance x y closed open))
                            (lateral (+ (* rx uy) (* ry (- ux)))))
                       (if (and (<= minimal d reach) (> (+ (* rx ux) (* ry uy)) 0)
                                (or (zerop side) (> (* side lateral) 0)))
                           1d0 0d0)))
                   'container-handle-ring 4))
                (register-cost-function
                 costmap
                 (lambda (x y)
                   (flet ((dist (p) (sqrt (+ (expt (- x (cl-transforms:x p)) 2)
                                             (expt (- y (cl-transforms:y p)) 2)))))
                     (if (and (<= (dist handle) reach)
                              (>= (dist closed) minimal) (>= (dist open) minimal))
                         1d0 0d0)))
                 'container-handle-ring 4)))
          costmap)))))

;;; ---- the restricted area ---------------------------------------------------------------------------

(defun kitchen-restricted-area (x y)
  "1 where the robot may stand in the IAI kitchen, else 0: not beyond x 1.2 (the sink and
fridge row), and inside the kitchen's walls."
  (macrolet ((area ()
               '(cond ((> x 1.2d0) 0d0)
                      ((and (> x 0.5d0) (< -1.5d0 y 2d0)) 1d0)
                      ((and (> x 0d0) (< -1.5d0 y 1d0)) 1d0)
                      ((and (> x -1.5d0) (< -1.5d0 y 2.5d0)) 1d0)
                      ((and (> x -4d0) (< -1d0 y 1d0)) 1d0)
                      (t 0d0))))
    ;; a costmap asks at every cell centre, with double-floats
    (if (and (typep x 'double-float) (typep y 'double-float))
        (locally (declare (type double-float x y) (optimize speed)) (area))
        (area))))

(defvar *restricted-area-function* nil
  "NIL, or a function (x y) -> 0 or 1 restricting where VISIBLE-FOR and REACHABLE-FOR base poses
may be (e.g. #'KITCHEN-RESTRICTED-AREA, which the household scenario sets).")

(defun restricted-area-applies-p (designator)
  "True when *RESTRICTED-AREA-FUNCTION* is set and DESIGNATOR's object is not on the robot."
  (and *restricted-area-function* (not (held-item designator :object))))

(defun restricted-area-costmap ()
  (let ((costmap (make-location-costmap)))
    (register-cost-function costmap *restricted-area-function* 'restricted-area 5)
    costmap))

;;; ---- Prolog ----------------------------------------------------------------------------------------

(def-fact-group household-location-costmaps (desig-costmap)
  (<- (desig-costmap ?designator ?costmap)
    (desig:loc-desig? ?designator)
    (desig:desig-prop ?designator (:in ?container))
    (lisp-fun in-costmap ?designator ?container ?costmap))
  (<- (desig-costmap ?designator ?costmap)
    (desig:loc-desig? ?designator)
    (desig:desig-prop ?designator (:above ?container))
    (lisp-fun above-costmap ?designator ?container ?costmap))
  (<- (desig-costmap ?designator ?costmap)
    (desig:loc-desig? ?designator)
    (desig:desig-prop ?designator (:side ?sides))
    (lisp-fun side-costmap ?designator ?sides ?costmap))
  (<- (desig-costmap ?designator ?costmap)
    (desig:loc-desig? ?designator)
    (desig:desig-prop ?designator (:range ?distance))
    (lisp-fun range-costmap ?designator ?distance nil ?costmap))
  (<- (desig-costmap ?designator ?costmap)
    (desig:loc-desig? ?designator)
    (desig:desig-prop ?designator (:range-invert ?distance))
    (lisp-fun range-costmap ?designator ?distance t ?costmap))
  (<- (desig-costmap ?designator ?costmap)
    (desig:loc-desig? ?designator)
    (desig:desig-prop ?designator (:context ?context))
    (lisp-fun slot-costmap ?designator ?context ?costmap))
  (<- (desig-costmap ?designator ?costmap)
    (desig:loc-desig? ?designator)
    (lisp-pred has-relation-p ?designator)
    (lisp-fun relations-costmap ?designator ?costmap))
  (<- (desig-costmap ?designator ?costmap)
    (desig:loc-desig? ?designator)
    (desig:desig-prop ?designator (:orientation ?orientation))
    (lisp-fun support-aligned-costmap ?designator ?orientation ?costmap))
  (<- (desig-costmap ?designator ?costmap)
    (desig:loc-desig? ?designator)
    (desig:desig-prop ?designator (:reachable-for ?robot))
    (desig:desig-prop ?designator (:object ?container))
    (lisp-pred container-designator-p ?container)
    (lisp-fun container-reach-costmap ?designator ?robot ?container ?costmap))
  (<- (desig-costmap ?designator ?costmap)
    (desig:loc-desig? ?designator)
    (or (desig:desig-prop ?designator (:visible-for ?_))
        (desig:desig-prop ?designator (:reachable-for ?_)))
    (lisp-pred restricted-area-applies-p ?designator)
    (lisp-fun restricted-area-costmap ?costmap)))
