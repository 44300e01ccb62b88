;;;; Spatial relations to another object of the belief state: (left-of O), (right-of O),
;;;; (in-front-of O), (behind O) with (threshold T), (near O) and (far-from O).  Directions are
;;;; those of a person at the edge of the supporting surface nearest to O.

(in-package :cram-location-costmap)

(defparameter *relation-keys* '(:left-of :right-of :in-front-of :behind :near :far-from)
  "The location designator keys that relate a place to another object.")

(defparameter *default-relation-threshold* 0.2d0
  "The default (threshold T) of the directional relations: places whose direction from the
reference object is more than acos(T) off the relation's axis are excluded.")

(defparameter *support-tolerance* 0.03d0
  "Metres an object's bottom may lie below the top of the surface it rests on.")

(defun relation-reference (designator)
  "(values key reference-designator) of DESIGNATOR's first relation."
  (loop for key in *relation-keys*
        for value = (desig:desig-prop-value designator key)
        when value return (values key value)))

(defun relation-object (reference key designator)
  (unless (typep reference 'desig:object-designator)
    (error "Location designator ~a: (~(~a~) ~s), expected an object designator." designator key reference))
  (or (object-designator-world-object reference)
      (error "Location designator ~a: the ~(~a~) object ~a is not in the belief state (objects: ~
              ~{~s~^ ~})." designator key reference (btr:object-names btr:*current-bullet-world*))))

(defun supporting-body (object &optional (world btr:*current-bullet-world*))
  "The BODY of the highest environment link under OBJECT's origin whose top is at most
*SUPPORT-TOLERANCE* above OBJECT's bottom; NIL when there is none."
  (multiple-value-bind (olo) (btr:aabb object)
    (let* ((origin (cl-transforms:origin (btr:pose object)))
           (ox (float (cl-transforms:x origin) 1d0)) (oy (float (cl-transforms:y origin) 1d0))
           (limit (float (+ (cl-transforms:z olo) *support-tolerance*) 1d0))
           (best nil) (best-top 0d0))
      (declare (type double-float ox oy limit best-top))
      (dolist (env (static-obstacles world))
        (let ((boxes (btr:link-aabbs env)))
          (declare (type (simple-array double-float (*)) boxes))
          (loop for link in (btr:link-names env)
                for k of-type fixnum from 0 by 6
                do (let ((top (aref boxes (+ k 5))))
                     (when (and (<= (aref boxes k) ox (aref boxes (+ k 3)))
                                (<= (aref boxes (+ k 1)) oy (aref boxes (+ k 4)))
                                (<= top limit)
                                (or (null best) (> top best-top)))
                       (setf best-top top best (cons env link)))))))
      (and best (link-body (car best) (cdr best))))))

(defun relation-support-body (designator)
  "The surface the reference object of DESIGNATOR's relation rests on."
  (multiple-value-bind (key reference) (relation-reference designator)
    (unless key
      (error "Location designator ~a has no ON, IN, ABOVE or relation (~{~(~a~)~^, ~}) to align with."
             designator *relation-keys*))
    (let ((object (relation-object reference key designator)))
      (or (supporting-body object)
          (error "Location designator ~a: nothing of the environment supports ~s, the ~(~a~) ~
                  object." designator (btr:name object) key)))))

;;; ---- directions ------------------------------------------------------------------------------------

(defun closest-edge (support x y)
  "The edge (:FRONT :BACK :LEFT :RIGHT) of the SUPPORT body nearest the map point (X Y),
distances to the longer edges counted shorter by the ratio of the sides. As in CRAM, the sides
are the extents of the support's box in the map, compared with the point in the support's
frame: on the dining table, turned a quarter, a person sits at its front (map -y) edge."
  (multiple-value-bind (lx ly) (body-local-point support x y)
    (multiple-value-bind (hx hy) (body-map-half-extent support)
      (let ((ratio-x (if (> hx hy) (/ hx (max hy 1d-6)) 1d0))
            (ratio-y (if (> hy hx) (/ hy (max hx 1d-6)) 1d0)))
        (if (< (* ratio-x (- hx (abs lx))) (* ratio-y (- hy (abs ly))))
            (if (> lx 0) :back :front)
            (if (> ly 0) :left :right))))))

(defparameter *relation-axes*
  '((:front (:left-of :y >) (:right-of :y <) (:behind :x >) (:in-front-of :x <))
    (:back (:left-of :y <) (:right-of :y >) (:behind :x <) (:in-front-of :x >))
    (:right (:left-of :x <) (:right-of :x >) (:behind :y >) (:in-front-of :y <))
    (:left (:left-of :x >) (:right-of :x <) (:behind :y <) (:in-front-of :y >)))
  "Edge of the support -> relation -> axis of the support frame and sign of the direction.")

(defun potential-field-function (relation edge reference support threshold)
  "1 along the RELATION's direction from the REFERENCE point, falling as the cosine of the
angle off it, 0 where that cosine is below THRESHOLD or on the other side."
  (destructuring-bind (axis sign) (rest (assoc relation (rest (assoc edge *relation-axes*))))
    (let* ((yaw (body-yaw support)) (c (float (cos yaw) 1d0)) (s (float (sin yaw) 1d0))
           (rx (float (cl-transforms:x reference) 1d0)) (ry (float (cl-transforms:y reference) 1d0))
           (along-x (eq axis :x)) (positive (eq sign '>))
           (threshold (float threshold 1d0)))
      (declare (type double-float c s rx ry threshold))
      (lambda (x y)
        (let* ((dx (- (float x 1d0) rx)) (dy (- (float y 1d0) ry))
               (lx (+ (* c dx) (* s dy))) (ly (- (* c dy) (* s dx)))
               (coord (if along-x lx ly))
               (norm (sqrt (+ (* lx lx) (* ly ly)))))
          (declare (type double-float dx dy lx ly coord norm))
          (if (and (> norm 1d-9) (if positive (> coord 0d0) (< coord 0d0))
                   (> (/ (abs coord) norm) threshold))
              (/ (abs coord) norm)
              0d0))))))

;;; ---- sizes for near and far ----------------------------------------------------------------------

(defparameter *circular-types* '(:bowl :plate :pancake-maker) "Types measured by their diameter.")
(defparameter *handle-sizes* '((:mug 0.04d0) (:pot 0.12d0)) "Type -> metres its handles add.")
(defparameter *relation-paddings* '((:pot 0.04d0) (:bowl 0.03d0) (:mug 0.01d0) (:plate 0.005d0)
                                    (:knife 0.005d0) (:cup 0.1d0))
  "Type -> metres kept free around objects of that type by near and far-from.")
(defparameter *default-relation-padding* 0.01d0 "Padding of the other types.")
(defparameter *unknown-object-size* '(0.1d0 0.1d0)
  "(size padding) of a FOR object that is not in the belief state.")

(defun relation-size (object)
  "(values size padding) of OBJECT for near and far-from."
  (let* ((types (mapcar #'keyword-of (btr:item-types object)))
         (extent (btr:bounding-box object))
         (ex (cl-transforms:x extent)) (ey (cl-transforms:y extent))
         (handle (some (lambda (type) (second (assoc type *handle-sizes*))) types)))
    (values (cond ((some (lambda (type) (member type *circular-types*)) types) ex)
                  (handle (- (max ex ey) handle))
                  (t (min ex ey)))
            (or (some (lambda (type) (second (assoc type *relation-paddings*))) types)
                *default-relation-padding*))))

(defun near-far-ring (key ref ref-pad for for-pad)
  "(values min-radius max-radius) of (near ...) or (far-from ...)."
  (let ((min (if (eq key :near)
                 (+ (/ ref 2) ref-pad for-pad (/ for 2))
                 (if (> ref for)
                     (+ (* 1.5d0 ref) (* 3 ref-pad) for-pad (/ for 2))
                     (+ (/ ref 2) ref-pad (* 3 for-pad) (* 1.5d0 for))))))
    (values min (+ min (* (+ ref for) 0.5d0 (if (eq key :near) 1d0 5d0))))))

;;; ---- the costmaps ------------------------------------------------------------------------------------

(defun relation-threshold (designator)
  (multiple-value-bind (value found) (desig:desig-prop-value designator :threshold)
    (if found (check-real value "(threshold ...)" designator :min 0 :max 1) *default-relation-threshold*)))

(defun relations-costmap (designator)
  "Every relation of DESIGNATOR to other objects in one costmap, clear (by half the FOR
object's size, or, with an ORIENTATION, by its extents turned as it will lie) of the items on
the reference object's support; without ON, IN or ABOVE also
the support's box (shrunk for the FOR object), its top as the height and, for a FOR object,
quarter turns about the vertical as orientations (MAKE-QUARTER-TURNS-ORIENTATION-GENERATOR)."
  (let ((costmap (make-location-costmap))
        (threshold (relation-threshold designator)))
    (multiple-value-bind (for-half for-lift for-object) (for-object-geometry designator)
      (multiple-value-bind (for-size for-pad)
          (if for-object (relation-size for-object) (values-list *unknown-object-size*))
        (loop for key in *relation-keys*
              do (dolist (reference (desig:desig-prop-values designator key))
                   (let* ((object (relation-object reference key designator))
                          (point (cl-transforms:origin (btr:pose object))))
                     (if (member key '(:near :far-from))
                         (multiple-value-bind (ref ref-pad) (relation-size object)
                           (multiple-value-bind (r0 r1) (near-far-ring key ref ref-pad for-size for-pad)
                             (register-cost-function costmap (make-range-cost-function point r0 :invert t)
                                                     key 2)
                             (register-cost-function costmap (make-range-cost-function point r1) key 2)))
                         (let ((support (or (supporting-body object) (relation-support-body designator))))
                           (register-cost-function
                            costmap
                            (potential-field-function key (closest-edge support (cl-transforms:x point)
                                                                        (cl-transforms:y point))
                                                      point support threshold)
                            key 7))))))
        ;; a FOR object is put down clear of the items already on the support by half its
        ;; size, as on a surface (ON-COSTMAP), not into them
        (when for-object
          (let* ((support (relation-support-body designator))
                 (lo (body-lo support)) (hi (body-hi support))
                 (items (supporting-items (cl-transforms:x lo) (cl-transforms:y lo)
                                          (cl-transforms:x hi) (cl-transforms:y hi)
                                          (cl-transforms:z hi) for-object)))
            (when items
              (register-cost-function
               costmap
               (if (desig:desig-prop-value designator :orientation)
                   ;; laid along the support's nearest edge (support-aligned): its own
                   ;; extents, turned as it will lie
                   (let ((body (orientation-body designator)))
                     (multiple-value-bind (hx hy) (object-half-extents for-object)
                       (turned-items-free-space-function items hx hy (nearest-edge-yaw-function body))))
                   (items-free-space-function items for-half))
               'relation-free-space 5))))
        (unless (some (lambda (key) (desig:desig-prop-value designator key)) '(:on :in :above))
          (let ((support (relation-support-body designator)))
            (register-cost-function costmap
                                    (if (body-link support)
                                        (link-top-function (body-object support) (body-link support)
                                                           (or for-half 0d0))
                                        (shrunk-box-function (body-lo support) (body-hi support)
                                                             (or for-half 0d0)))
                                    'supporting-object 9)
            (register-height-generator costmap (make-constant-height-function
                                                (+ (cl-transforms:z (body-hi support)) for-lift)))
            (register-orientation-generator costmap (if for-object
                                                        (make-quarter-turns-orientation-generator)
                                                        (make-identity-orientation-generator)))))
        costmap))))

(defun has-relation-p (designator)
  (and (relation-reference designator) t))
