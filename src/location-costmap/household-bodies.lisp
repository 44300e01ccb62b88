;;;; The bodies household location designators refer to: a link of the environment named by
;;;; URDF-NAME (and PART-OF), a level inside it (LEVEL), or an object of the belief state;
;;;; their poses and boxes in the current belief state, in the map and in their own frame.

(in-package :cram-location-costmap)

(defstruct (body (:constructor make-body (pose lo hi &key object link)))
  "A reference body: its POSE (map), world AABB corners LO and HI, the belief-state OBJECT
(an environment or item) and, for an environment part, its LINK name."
  pose lo hi object link)

(defun keyword-of (value)
  (and (symbolp value) value (intern (symbol-name value) :keyword)))

(defun designator-environment (designator what &optional (world btr:*current-bullet-world*))
  "The environment object DESIGNATOR's PART-OF names (default: the environment)."
  (let ((part-of (desig:desig-prop-value designator :part-of)))
    (if part-of
        (let ((env (find-world-object part-of world)))
          (unless (and env (btr:robot-object-p env))
            (error "~a: ~s (PART-OF of ~a) is not an environment of the belief state; objects: ~
                    ~{~s~^ ~}." what part-of designator (btr:object-names world)))
          env)
        (or (btr:get-environment-object world)
            (error "~a: ~a has no PART-OF and the belief state has no environment." what designator)))))

(defun designator-link (designator what &optional (world btr:*current-bullet-world*))
  "(values environment link-name) of the object DESIGNATOR with a URDF-NAME, or NIL."
  (let ((urdf-name (desig:desig-prop-value designator :urdf-name)))
    (when urdf-name
      (unless (or (stringp urdf-name) (and (symbolp urdf-name) urdf-name))
        (error "~a: URDF-NAME ~s of ~a, expected a link name such as sink-area-surface."
               what urdf-name designator))
      (let ((env (designator-environment designator what world))
            (link (urdf-link-name urdf-name)))
        (unless (btr:link-exists-p env link)
          (error "~a: ~s (from URDF-NAME ~s) is not a link of ~s." what link urdf-name (btr:name env)))
        (values env link)))))

(defun link-body (env link)
  (multiple-value-bind (lo hi) (btr:aabb env (btr:link-index env link))
    (make-body (btr:link-pose env link) lo hi :object env :link link)))

(defun designator-body (designator what &key (level t) (world btr:*current-bullet-world*))
  "The BODY the object DESIGNATOR names: with LEVEL, its LEVEL link when it has one; else its
URDF-NAME link; else its belief-state object.  An error naming DESIGNATOR when there is none."
  (unless (typep designator 'desig:object-designator)
    (error "~a: expected an object designator such as (an object (type drawer) (urdf-name ~
            sink-area-left-upper-drawer-main) (part-of iai-kitchen)), got ~s." what designator))
  (multiple-value-bind (env link) (designator-link designator what world)
    (cond ((and env level (designator-level designator))
           (multiple-value-bind (value invert) (designator-level designator)
             (link-body env (container-level-link env link value what :invert invert))))
          (env (link-body env link))
          (t (let ((object (object-designator-world-object designator world)))
               (unless object
                 (error "~a: ~a names no link (URDF-NAME) and no object of the belief state ~
                         (objects: ~{~s~^ ~})." what designator (btr:object-names world)))
               (multiple-value-bind (lo hi) (btr:aabb object)
                 (make-body (btr:pose object) lo hi :object object)))))))

;;; ---- levels ------------------------------------------------------------------------------------

(defparameter *level-link-patterns* '("_board" "_level" "_shelf" "Floor")
  "Substrings of the names of links that are levels (boards, shelves) of a container.")

(defun level-link-name-p (name)
  (some (lambda (p) (search p name)) *level-link-patterns*))

(defun urdf-link (env link)
  "The CL-URDF link named LINK of the environment ENV, or NIL."
  (let ((urdf (btr:urdf env)))
    (and urdf (gethash link (cl-urdf:links urdf)))))

(defun child-links (env link)
  "The names of the links right below LINK of ENV, in URDF document order."
  (let ((l (urdf-link env link)))
    (and l (mapcar (lambda (j) (cl-urdf:name (cl-urdf:child j))) (cl-urdf:child-joints-in-order l)))))

(defun level-links (env link)
  "The level links of the container LINK: its descendants named as levels, found through level
links only.  A container whose levels hang under another part (the fridge door's shelves under
its block) has none so; then its descendants named as levels that end in _bottom are its levels."
  (labels ((strict (l) (loop for c in (child-links env l)
                             when (level-link-name-p c) append (cons c (strict c))))
           (any (l) (loop for c in (child-links env l)
                          append (if (and (level-link-name-p c) (search "_bottom" c))
                                     (cons c (any c))
                                     (any c)))))
    (or (strict link) (any link))))

(defun designator-level (designator)
  "(values level invert) of the container DESIGNATOR: its (level L), or its (level-invert L)
with INVERT true; NIL when it has neither."
  (multiple-value-bind (level found) (desig:desig-prop-value designator :level)
    (if found
        (values level nil)
        (multiple-value-bind (level found) (desig:desig-prop-value designator :level-invert)
          (and found (values level t))))))

(defun container-level-link (env link level what &key invert)
  "The link of LEVEL (:TOPMOST, :BOTTOMMOST, :MIDDLE or a positive integer N, the Nth from the
bottom; from the top with INVERT) among the level links of the container LINK, ordered by the
tops of their boxes."
  (let* ((levels (sort (mapcar (lambda (l)
                                 (cons l (cl-transforms:z (nth-value 1 (btr:aabb env (btr:link-index env l))))))
                               (level-links env link))
                       (if invert #'> #'<) :key #'cdr))
         (n (length levels))
         (level (if (integerp level) level (keyword-of level))))
    (when (zerop n)
      (error "~a: the container ~s has no levels (links named ~{*~a*~^, ~}) for (level ~s)."
             what link *level-link-patterns* level))
    (car (nth (cond ((eq level :bottommost) 0)
                    ((eq level :topmost) (1- n))
                    ((eq level :middle) (floor n 2))
                    ((and (integerp level) (<= 1 level n)) (1- level))
                    (t (error "~a: (level ~s) of ~s, expected TOPMOST, BOTTOMMOST, MIDDLE or an ~
                               integer from 1 to ~d." what level link n)))
              levels))))

;;; ---- frames -------------------------------------------------------------------------------------

(defun body-local-point (body x y)
  "The map point (X Y) in BODY's frame, as (values x y); BODY's z axis is taken as up."
  (funcall (body-local-function body) x y))

(defun body-local-function (body)
  "A function (x y) -> (values x y) from the map into BODY's frame (its z axis taken as up)."
  (let* ((yaw (body-yaw body)) (c (cos yaw)) (s (sin yaw))
         (o (cl-transforms:origin (body-pose body)))
         (ox (cl-transforms:x o)) (oy (cl-transforms:y o)))
    (declare (type double-float c s ox oy))
    (lambda (x y)
      (let ((dx (- (float x 1d0) ox)) (dy (- (float y 1d0) oy)))
        (values (+ (* c dx) (* s dy)) (- (* c dy) (* s dx)))))))

(defun body-yaw (body)
  "The yaw (radians) of BODY's x axis in the map."
  (let ((x (cl-transforms:rotate (cl-transforms:orientation (body-pose body))
                                 (cl-transforms:make-3d-vector 1 0 0))))
    (atan (cl-transforms:y x) (cl-transforms:x x))))

(defun body-map-half-extent (body)
  "(values half-x half-y) of BODY's box in the map."
  (values (/ (- (cl-transforms:x (body-hi body)) (cl-transforms:x (body-lo body))) 2)
          (/ (- (cl-transforms:y (body-hi body)) (cl-transforms:y (body-lo body))) 2)))

(defun body-local-extent (body)
  "(values half-x half-y) of BODY's box in its own frame (from its world box and yaw)."
  (let* ((yaw (body-yaw body)) (c (abs (cos yaw))) (s (abs (sin yaw)))
         (wx (/ (- (cl-transforms:x (body-hi body)) (cl-transforms:x (body-lo body))) 2))
         (wy (/ (- (cl-transforms:y (body-hi body)) (cl-transforms:y (body-lo body))) 2)))
    ;; the world box of a box turned by yaw: wx = c hx + s hy, wy = s hx + c hy
    (let ((det (- (* c c) (* s s))))
      (if (> (abs det) 0.2d0)
          (values (max 0d0 (/ (- (* c wx) (* s wy)) det)) (max 0d0 (/ (- (* c wy) (* s wx)) det)))
          (values (min wx wy) (min wx wy))))))

(defun for-object-geometry (designator)
  "(values half-size lift object) of the FOR object of the location DESIGNATOR standing upright
(OBJECT-FOOTPRINT) and the belief-state object (FOR-OBJECT); (values nil 0 nil) when it has
none in the belief state."
  (let* ((for (desig:desig-prop-value designator :for))
         (object (for-object designator)))
    (when (and for (not (typep for 'desig:object-designator)))
      (error "Location designator ~a: (for ~s), expected an object designator." designator for))
    (if object
        (multiple-value-bind (half lift) (object-footprint object)
          (values half lift object))
        (values nil 0d0 nil))))
