;;;; Household location designators on, in and above the kitchen's furniture: (in C) with
;;;; (level L), (above C) with (z-offset Z), (side S), (range R), (range-invert R),
;;;; (orientation support-aligned), (context table-setting) (object-count N), and the predefined
;;;; (attachments (NAME ...)) of the dishwasher tray.  Every region is read from the current
;;;; belief state, so an opened drawer moves its IN region.

(in-package :cram-location-costmap)

(defparameter *in-height-above-bottom* 0.04d0
  "Metres above the bottom of a container's box at which (in C) places an object's bottom.")

(defun check-real (value what designator &key (min -1d3) (max 1d3))
  (unless (and (finite-real-p value) (<= min value max))
    (error "Location designator ~a: ~a ~s, expected a real from ~a to ~a." designator what value min max))
  (to-double value))

(defun shrunk-box-function (lo hi margin)
  "The rectangle of the box LO..HI shrunk by MARGIN on every side (at least its centre line)."
  (let ((x0 (cl-transforms:x lo)) (y0 (cl-transforms:y lo))
        (x1 (cl-transforms:x hi)) (y1 (cl-transforms:y hi)))
    (let ((cx (/ (+ x0 x1) 2)) (cy (/ (+ y0 y1) 2)))
      (make-rectangle-cost-function (min cx (+ x0 margin)) (min cy (+ y0 margin))
                                    (max cx (- x1 margin)) (max cy (- y1 margin))))))

(defun box-region-costmap (designator body name height)
  "A costmap of BODY's box, shrunk for the FOR object, at HEIGHT plus the FOR object's lift."
  (multiple-value-bind (half lift) (for-object-geometry designator)
    (let ((costmap (make-location-costmap)))
      (register-cost-function costmap (shrunk-box-function (body-lo body) (body-hi body) (or half 0d0))
                              name 0)
      (register-height-generator costmap (make-constant-height-function (+ height lift)))
      (register-orientation-generator costmap (make-identity-orientation-generator))
      costmap)))

(defun in-costmap (designator container)
  "(in CONTAINER): the container's box at its bottom + *IN-HEIGHT-ABOVE-BOTTOM*, or with
(level L) inside CONTAINER the box of that level at its top."
  (let ((body (designator-body container "IN")))
    (box-region-costmap designator body 'in-box
                        (if (designator-level container)
                            (cl-transforms:z (body-hi body))
                            (+ (cl-transforms:z (body-lo body)) *in-height-above-bottom*)))))

(defun above-costmap (designator container)
  "(above CONTAINER) (z-offset Z): the container's box at its top + Z."
  (let ((body (designator-body container "ABOVE"))
        (z (multiple-value-bind (value found) (desig:desig-prop-value designator :z-offset)
             (if found (check-real value "(z-offset ...)" designator :min -2 :max 2) 0d0))))
    (box-region-costmap designator body 'above-box (+ (cl-transforms:z (body-hi body)) z))))

(defun reference-body (designator what)
  "The body of DESIGNATOR's ON, IN or ABOVE object, with its level."
  (let ((reference (some (lambda (key) (desig:desig-prop-value designator key)) '(:on :in :above))))
    (unless reference
      (error "Location designator ~a: ~a needs an ON, IN or ABOVE object to refer to." designator what))
    (designator-body reference what)))

;;; ---- side and range -------------------------------------------------------------------------------

(defparameter *sides* '((:front :x <) (:back :x >) (:right :y <) (:left :y >))
  "Each side of a body: the axis of its frame and the sign of the half-plane.")

(defun side-cost-function (body sides designator)
  (let ((entries (mapcar (lambda (s)
                           (or (assoc (keyword-of s) *sides*)
                               (error "Location designator ~a: (side ~s), expected FRONT, BACK, ~
                                       LEFT, RIGHT or a list of them." designator s)))
                         (cond ((atom sides) (list sides))
                               ((null (cdr (last sides))) sides)
                               (t (error "Location designator ~a: (side ~s), expected a side or a ~
                                          list of sides." designator sides))))))
    (when (null entries)
      (error "Location designator ~a: (side ~s) names no side." designator sides))
    (let ((local (body-local-function body)))
      (lambda (x y)
        (multiple-value-bind (lx ly) (funcall local x y)
          (if (every (lambda (e) (let ((v (if (eq (second e) :x) lx ly)))
                                   (if (eq (third e) '<) (< v 0) (> v 0))))
                     entries)
              1d0 0d0))))))

(defun side-costmap (designator sides)
  "(side S) or (side (S1 S2)): the half-planes of the reference body's frame; front x < 0,
back x > 0, right y < 0, left y > 0."
  (let ((costmap (make-location-costmap))
        (body (reference-body designator "SIDE")))
    (register-cost-function costmap (side-cost-function body sides designator) 'side 3)
    costmap))

(defun range-costmap (designator distance invert)
  "(range R): within R metres of the reference body's origin; (range-invert R): beyond R."
  (let ((costmap (make-location-costmap))
        (body (reference-body designator (if invert "RANGE-INVERT" "RANGE")))
        (r (check-real distance (if invert "(range-invert ...)" "(range ...)") designator :min 0 :max 100)))
    (register-cost-function costmap (make-range-cost-function (body-pose body) r :invert invert)
                            (if invert 'range-invert 'range) 2)
    costmap))

;;; ---- orientation ---------------------------------------------------------------------------------

(defun orientation-body (designator)
  (if (some (lambda (key) (desig:desig-prop-value designator key)) '(:on :in :above))
      (reference-body designator "ORIENTATION")
      (relation-support-body designator)))

(defun nearest-edge-yaw-function (body)
  "A function (x y) -> NEAREST-EDGE-YAW of BODY at the map point (X Y); BODY's frame and box
are worked out once."
  (multiple-value-bind (hx hy) (body-local-extent body)
    (let ((local (body-local-function body))
          (yaw (body-yaw body)))
      (multiple-value-bind (cx cy)
          (funcall local
                   (/ (+ (cl-transforms:x (body-lo body)) (cl-transforms:x (body-hi body))) 2)
                   (/ (+ (cl-transforms:y (body-lo body)) (cl-transforms:y (body-hi body))) 2))
        (lambda (x y)
          (multiple-value-bind (px py) (funcall local x y)
            (let ((dx (- px cx)) (dy (- py cy)))
              (+ yaw
                 (if (< (- hx (abs dx)) (- hy (abs dy)))
                     (if (minusp dx) pi 0d0)
                     (if (minusp dy) (/ pi -2) (/ pi 2)))))))))))

(defun nearest-edge-yaw (body x y)
  "The yaw (map) of the outward normal of the edge of BODY's box nearest to the map point (X Y)."
  (funcall (nearest-edge-yaw-function body) x y))

(defun support-aligned-costmap (designator orientation)
  "(orientation support-aligned): the object's x axis along the outward normal of the edge of
the supporting body nearest to the pose, first pointing out of it, then into it."
  (unless (eq (keyword-of orientation) :support-aligned)
    (error "Location designator ~a: (orientation ~s), expected SUPPORT-ALIGNED." designator orientation))
  (let* ((costmap (make-location-costmap))
         (edge-yaw (nearest-edge-yaw-function (orientation-body designator))))
    (register-orientation-generator costmap (lambda (x y previous)
                                              (declare (ignore previous))
                                              (let ((yaw (funcall edge-yaw x y)))
                                                (list (yaw-quaternion yaw)
                                                      (yaw-quaternion (+ yaw pi))))))
    costmap))

;;; ---- table setting slots -------------------------------------------------------------------------

(defparameter *table-setting-paddings*
  '(("kitchen_island_surface" 0.1d0 0.1d0 0.8d0 0.1d0)
    ("dining_area_jokkmokk_table_main" 0.03d0 0.03d0 0.03d0 0.03d0)
    ("sink_area_surface" 0.03d0 0.03d0 0.03d0 0.03d0))
  "Surface link -> paddings (x+ x- y+ y-) in its frame that table-setting slots keep free.")

(defparameter *slot-sizes* '((:bowl 0.2d0 0.6d0) (:plate 0.5d0 0.8d0))
  "Object type -> (minimal maximal) slot size in metres; other types use *DEFAULT-SLOT-SIZE*.")

(defparameter *default-slot-size* '(0.2d0 0.8d0) "(minimal maximal) slot size of other types.")

(defparameter *slot-deviation* 0.08d0
  "Metres around the centre of a table-setting slot where objects are placed.")

(defun slot-points (half-long half-short long-axis count min max)
  "The slot centres (x y) of COUNT objects in a padded box: half of them (rounded up) along the
preferred (+) long edge, the rest along the other one, MIN metres in from the edge."
  (let* ((count (min count (* 2 (floor (* 2 half-long) min))))
         (preferred (ceiling count 2)) (other (floor count 2))
         (short (- half-short (/ min 2)))
         (distance (min max (/ (* 2 half-long) (max 1 preferred)))))
    (flet ((row (n s)
             (loop repeat n
                   for along = (* (/ (1- n) 2) distance) then (- along distance)
                   collect (if (eq long-axis :x) (list along s) (list s along)))))
      (append (row preferred short) (row other (- short))))))

(defun slot-costmap (designator context)
  "(context table-setting) (for O) (object-count N) on a surface: N slots in two rows, places
within *SLOT-DEVIATION* of their centres. As in CRAM, the rows run along the axis of the
surface's frame that is named by the longer side of its box in the map, MIN slot size in from
the other two edges (so a surface turned a quarter has its rows across its halves)."
  (unless (eq (keyword-of context) :table-setting)
    (error "Location designator ~a: (context ~s), expected TABLE-SETTING." designator context))
  (let* ((surface (desig:desig-prop-value designator :on))
         (body (if surface
                   (designator-body surface "CONTEXT")
                   (error "Location designator ~a: (context table-setting) needs an ON surface." designator)))
         (count (multiple-value-bind (n found) (desig:desig-prop-value designator :object-count)
                  (cond ((not found) 1)
                        ((typep n '(integer 1 100)) n)
                        (t (error "Location designator ~a: (object-count ~s), expected an integer ~
                                   from 1 to 100." designator n)))))
         (for (desig:desig-prop-value designator :for))
         (type (and (typep for 'desig:object-designator) (keyword-of (desig:desig-prop-value for :type))))
         (sizes (or (cdr (assoc type *slot-sizes*)) *default-slot-size*))
         (paddings (or (cdr (assoc (body-link body) *table-setting-paddings* :test #'equal))
                       '(0d0 0d0 0d0 0d0))))
    ;; as CRAM: the extents of the surface's box in the map, the slots in the surface's frame
    ;; (for the dining table, turned a quarter, the rows lie across its front and back halves)
    (multiple-value-bind (hx hy) (body-map-half-extent body)
      (destructuring-bind (px+ px- py+ py-) paddings
        (let* ((phx (max 0d0 (- hx (/ (+ px+ px-) 2)))) (phy (max 0d0 (- hy (/ (+ py+ py-) 2))))
               (shift-x (/ (- px+ px-) 2)) (shift-y (/ (- py+ py-) 2))
               (points (if (>= phx phy)
                           (slot-points phx phy :x count (first sizes) (second sizes))
                           (slot-points phy phx :y count (first sizes) (second sizes))))
               (d2 (* *slot-deviation* *slot-deviation*))
               (local (body-local-function body))
               (costmap (make-location-costmap)))
          (register-cost-function
           costmap
           (lambda (x y)
             (multiple-value-bind (lx ly) (funcall local x y)
               (let ((px (+ lx shift-x)) (py (+ ly shift-y)))
                 (if (loop for (sx sy) in points
                           thereis (<= (+ (expt (- px sx) 2) (expt (- py sy) 2)) d2))
                     1d0 0d0))))
           'slot-generator 6)
          costmap)))))

;;; ---- attachments ------------------------------------------------------------------------------------

(defparameter *attachments*
  '((:dish-washer-drawer-right :bowl (0.03d0 0.15d0 0.2d0) (0 0 0 1))
    (:dish-washer-drawer-left-flipped-around-x :cup (0.06d0 -0.19d0 0.22d0) (1 0 0 0))
    (:dish-washer-drawer-left-flipped-around-y :cup (0.06d0 -0.19d0 0.22d0) (0 1 0 0))
    (:dish-washer-drawer-center :spoon (0.04d0 0 0.03d0) (0 0 0 1)))
  "Predefined attachments: name, object type, pose (xyz, quaternion) in the frame of the body
the location is on, in or above (the dishwasher tray).")

(defun attachment-poses (designator)
  "The map poses of DESIGNATOR's (attachments (NAME ...)) on its reference body."
  (let* ((names (desig:desig-prop-value designator :attachments))
         (names (cond ((atom names) (list names))
                      ((null (cdr (last names))) names)
                      (t (error "Location designator ~a: (attachments ~s), expected a list of ~
                                 attachment names." designator names))))
         (body (reference-body designator "ATTACHMENTS"))
         (frame (cl-transforms:pose->transform (body-pose body))))
    (loop for name in names
          for entry = (or (assoc (keyword-of name) *attachments*)
                          (error "Location designator ~a: unknown attachment ~s; known: ~{~(~a~)~^, ~}."
                                 designator name (mapcar #'first *attachments*)))
          collect (destructuring-bind (xyz q) (cddr entry)
                    (cl-transforms-stamped:pose->pose-stamped
                     "map" 0d0
                     (cl-transforms:transform->pose
                      (cl-transforms:transform*
                       frame (cl-transforms:make-transform
                              (apply #'cl-transforms:make-3d-vector xyz)
                              (apply #'cl-transforms:make-quaternion q)))))))))

(defun attachments-location-generator (designator)
  "Location generator: the poses of the designator's predefined ATTACHMENTS, before any
costmap sample."
  (if (and (typep designator 'desig:location-designator)
           (nth-value 1 (desig:desig-prop-value designator :attachments)))
      (attachment-poses designator)
      nil))

(desig:register-location-generator 15 attachments-location-generator
  "The predefined attachment poses (e.g. the dishwasher tray's slots) of (attachments ...).")
