;;;; Objects of a reasoning world: kinds registered with DEFINE-OBJECT-KIND, poses, colours,
;;;; collision filters, mesh keywords.

(in-package :cram-bullet-reasoning)

;;; ---- numbers and poses ---

(defparameter *max-coordinate* 1d6
  "Largest magnitude (metres) of a position coordinate given to a world (object poses): a
larger one is refused with an error naming it (Bullet loses all precision far beyond).")

(defparameter *max-size* 1d4
  "Largest size, radius or height (metres) of an object added to a world.")

(defparameter *max-mass* 1d6
  "Largest mass (kg) of an object added to a world.")

(defvar *single-float-doubles* (make-hash-table :test 'eql :synchronized t)
  "Single float → the double TO-DOUBLE makes of it (plans give the same few constants again and
again, and reading a printed float is slow).")

(defun to-double (x)
  "The real X as a double float; a single float by its printed decimal (0.2 → 0.2d0)."
  (if (typep x 'single-float)
      (or (gethash x *single-float-doubles*)
          (let ((d (let ((*read-default-float-format* 'double-float))
                     (values (read-from-string (let ((*read-default-float-format* 'single-float))
                                                 (prin1-to-string x)))))))
            (when (> (hash-table-count *single-float-doubles*) 4096)
              (clrhash *single-float-doubles*))
            (setf (gethash x *single-float-doubles*) d)))
      (coerce x 'double-float)))

(defun pose-in-fixed-frame (pose-stamped what)
  "POSE-STAMPED in CRAM-TF:*FIXED-FRAME* (the frame of the world): as it is when it is given in
that frame, else transformed there by CRAM-TF:*TRANSFORMER*; a frame the transformer does not
connect to the fixed frame is an error naming it."
  (let ((frame (cl-transforms-stamped:frame-id pose-stamped))
        (fixed cram-tf:*fixed-frame*))
    (flet ((same-frame-p (a b)
             ;; "/map" and "map" name the same frame; compared without copying the strings
             (string= a b :start1 (or (position #\/ a :test-not #'char=) (length a))
                          :start2 (or (position #\/ b :test-not #'char=) (length b)))))
      (cond ((same-frame-p frame fixed) pose-stamped)
            ((and (typep cram-tf:*transformer* 'cl-transforms-stamped:transformer)
                  (cl-transforms-stamped:can-transform cram-tf:*transformer* fixed frame))
             (cl-transforms-stamped:transform-pose-stamped
              cram-tf:*transformer* :target-frame fixed :pose pose-stamped))
            (t (btr-fail "~a ~s is given in the frame ~s, which is neither the world's frame ~s ~
                          (CRAM-TF:*FIXED-FRAME*) nor connected to it in CRAM-TF:*TRANSFORMER*"
                         what pose-stamped frame fixed))))))

(defun ensure-pose (pose &optional (what "pose"))
  "POSE as a CL-TRANSFORMS:POSE. Accepts a pose (or pose-stamped), ((x y z) (qx qy qz qw)),
or (x y z) (identity orientation)."
  (flet ((reals (l n) (and (listp l) (= (length l) n) (every #'realp l))))
    (cond ((cl-transforms-stamped:pose-stamped-p pose) (pose-in-fixed-frame pose what))
          ((cl-transforms:pose-p pose) pose)
          ((and (consp pose) (= (length pose) 2) (reals (first pose) 3) (reals (second pose) 4))
           (handler-case
               (cl-transforms:make-pose (apply #'cl-transforms:make-3d-vector (first pose))
                                        (apply #'cl-transforms:make-quaternion (second pose)))
             (error (e) (btr-fail "~a ~s is not a valid pose: ~a" what pose e))))
          ((reals pose 3)
           (cl-transforms:make-pose (apply #'cl-transforms:make-3d-vector pose)
                                    (cl-transforms:make-identity-rotation)))
          (t (btr-fail "~a is ~s, expected a pose or ((x y z) (qx qy qz qw))" what pose)))))

(defun pose->vector (pose &optional (what "pose"))
  "POSE (anything ENSURE-POSE accepts) as a double vector x y z qx qy qz qw."
  (let* ((p (ensure-pose pose what))
         (o (cl-transforms:origin p)) (q (cl-transforms:orientation p))
         (v (make-array 7 :element-type 'double-float)))
    (setf (aref v 0) (cl-transforms:x o) (aref v 1) (cl-transforms:y o) (aref v 2) (cl-transforms:z o)
          (aref v 3) (cl-transforms:x q) (aref v 4) (cl-transforms:y q) (aref v 5) (cl-transforms:z q)
          (aref v 6) (cl-transforms:w q))
    (loop for x across v
          unless (< (abs x) most-positive-double-float)
            do (btr-fail "~a ~s has a non-finite component" what pose))
    (loop for i below 3
          unless (<= (abs (aref v i)) *max-coordinate*)
            do (btr-fail "~a ~s: coordinate ~s is beyond ~g m (BTR::*MAX-COORDINATE*)"
                         what pose (aref v i) *max-coordinate*))
    v))

(defun vector->pose (v &optional (offset 0))
  "The CL-TRANSFORMS:POSE stored in V at OFFSET as x y z qx qy qz qw."
  (macrolet ((pose-of (v)
               `(cl-transforms:make-pose
                 (cl-transforms:make-3d-vector (aref ,v offset) (aref ,v (+ offset 1))
                                               (aref ,v (+ offset 2)))
                 (cl-transforms:make-quaternion (aref ,v (+ offset 3)) (aref ,v (+ offset 4))
                                                (aref ,v (+ offset 5)) (aref ,v (+ offset 6))))))
    ;; the native layer's vectors of doubles read without a generic AREF
    (if (and (typep v '(simple-array double-float (*))) (typep offset 'fixnum))
        (pose-of (the (simple-array double-float (*)) v))
        (pose-of v))))

;;; ---- collision filters ---------------------------------------------------------------------

(defparameter *collision-filter-bits*
  '((:default-filter . 1) (:static-filter . 2) (:kinematic-filter . 4) (:debris-filter . 8)
    (:sensor-trigger . 16) (:character-filter . 32) (:user-filter-1 . 64) (:user-filter-2 . 128)
    (:user-filter-3 . 256) (:user-filter-4 . 512) (:user-filter-5 . 1024) (:all-filter . -1))
  "Bullet's collision filter groups by keyword.")

(defun collision-group-bits (spec)
  "The filter bits of SPEC: a keyword of *COLLISION-FILTER-BITS*, a list of them, or an integer."
  (cond ((integerp spec) spec)
        ((keywordp spec)
         (or (cdr (assoc spec *collision-filter-bits*))
             (btr-fail "collision filter ~s is unknown, expected one of ~{~s~^ ~}"
                       spec (mapcar #'car *collision-filter-bits*))))
        ((listp spec) (reduce #'logior (mapcar #'collision-group-bits spec) :initial-value 0))
        (t (btr-fail "collision filter ~s, expected a keyword, a list of keywords or an integer" spec))))

;;; ---- object classes --------------------------------------------------------------------------

(defclass object ()
  ((name :initarg :name :reader name :documentation "The object's name (a symbol).")
   (world :initarg :world :reader world :documentation "The world the object lives in.")
   (handle :initarg :handle :reader object-handle :documentation "Native object handle.")
   (kind :initarg :kind :reader object-kind :documentation "The ADD-OBJECT type keyword.")
   (types :initarg :types :initform nil :accessor item-types
          :documentation "Item types (keywords), e.g. (:bottle).")
   (spec :initarg :spec :initform nil :reader object-spec
         :documentation "The ADD-OBJECT keys the object was made with."))
  (:documentation "A named object of a reasoning world, backed by a native body."))

(defclass item (object) ()
  (:documentation "A movable (or at least manipulable) object, e.g. a mesh or box."))

(defmethod print-object ((o object) stream)
  (print-unreadable-object (o stream :type t)
    (format stream "~s" (name o))))

(defmethod copy-object ((o object) world)
  (let ((copy (allocate-instance (class-of o))))
    (dolist (slot (sb-mop:class-slots (class-of o)))
      (let ((n (sb-mop:slot-definition-name slot)))
        (when (slot-boundp o n)
          (setf (slot-value copy n) (slot-value o n)))))
    (setf (slot-value copy 'world) world)
    copy))

(defun whandle (object) (world-handle (world object)))

(defgeneric pose (object)
  (:documentation "The pose of OBJECT in the world frame (for a rigid body of a link, the link's)."))

(defun object-gone-error (object where)
  "Signal a BTR-ERROR naming OBJECT when it was removed from its world or its world destroyed."
  (let ((world (world object)))
    (cond ((not (native:world-alive-p (world-handle world)))
           (btr-fail "~a: the world of object ~s has been destroyed (DESTROY-WORLD)" where (name object)))
          ((not (eq (object world (name object)) object))
           (btr-fail "~a: object ~s has been removed from its world (REMOVE-OBJECT)" where (name object))))))

(defmacro with-live-object ((object where) &body body)
  "Run BODY, a native call on OBJECT; when it fails because OBJECT or its world is gone, signal
an error naming OBJECT instead of its handle."
  `(handler-case (progn ,@body)
     (native:native-error (e)
       (object-gone-error ,object ,where)
       (error e))))

(defmethod pose ((o object))
  (vector->pose (with-live-object (o 'pose) (native:object-pose (whandle o) (object-handle o)))))

(defmethod pose ((x t))
  (btr-fail "POSE: expected an object of a Bullet world (see BTR:OBJECT), got ~s" x))

(defmethod world ((x t))
  (btr-fail "expected an object of a Bullet world (see BTR:OBJECT), got ~s" x))

(defgeneric (setf pose) (new-pose object)
  (:documentation "Teleport OBJECT to NEW-POSE; rigidly attached objects follow."))

(defstruct (pose-of (:constructor pose-of (name)))
  "What (SETF POSE)'s error messages call the pose they were given, \"pose of NAME\": written
only when a message is made."
  name)

(defmethod print-object ((what pose-of) stream)
  (format stream "pose of ~s" (pose-of-name what)))

(defmethod (setf pose) (new-pose (o object))
  (let ((v (pose->vector new-pose (pose-of (name o)))))
    (with-live-object (o '(setf pose)) (native:set-object-pose (whandle o) (object-handle o) v)))
  new-pose)

(defun object-pose (name &optional (world *current-bullet-world*))
  "The pose of the object NAME in WORLD; an error naming NAME when there is none."
  (pose (object-or-fail world name)))

(defun object-or-fail (world name)
  "The object NAME of WORLD or a BTR-ERROR naming it and the known objects."
  (or (object world name)
      (btr-fail "there is no object ~s in the world; known objects: ~{~s~^ ~}" name (object-names world))))

(defun item-type (object)
  "The first item type of OBJECT."
  (first (item-types object)))

(defun object-type (object) "Alias of ITEM-TYPE." (item-type object))

(defun aabb (object &optional link)
  "Axis-aligned bounding box of OBJECT (or its LINK index) as (values min-vector max-vector)."
  (let ((b (with-live-object (object 'aabb)
             (native:object-aabb (whandle object) (object-handle object) (or link -1)))))
    (values (cl-transforms:make-3d-vector (aref b 0) (aref b 1) (aref b 2))
            (cl-transforms:make-3d-vector (aref b 3) (aref b 4) (aref b 5)))))

(defun link-aabbs (object &optional out)
  "The axis-aligned bounding box of every link of the articulated OBJECT, as AABB gives each,
in one vector of doubles: min x y z, max x y z of link index 0, then of link 1, and so on (into
OUT, a double vector of at least 6 times LINK-COUNT, when given)."
  (unless (typep object 'robot-object)
    (btr-fail "LINK-AABBS: ~s is not an articulated object" object))
  (with-live-object (object 'link-aabbs)
    (native:robot-link-aabbs (whandle object) (object-handle object) out)))

(defun local-aabb (object &optional link)
  "The box of OBJECT's shapes (or its LINK index's) in its own frame, as (values min-vector
max-vector): the axis-aligned box an unturned copy of it standing at the origin would have."
  (let ((b (with-live-object (object 'local-aabb)
             (native:object-local-aabb (whandle object) (object-handle object) (or link -1)))))
    (values (cl-transforms:make-3d-vector (aref b 0) (aref b 1) (aref b 2))
            (cl-transforms:make-3d-vector (aref b 3) (aref b 4) (aref b 5)))))

(defun bounding-box (object)
  "Size of OBJECT's axis-aligned bounding box as a 3D-VECTOR."
  (multiple-value-bind (lo hi) (aabb object) (cl-transforms:v- hi lo)))

(defun object-color (object &optional link)
  "The RGBA colour of OBJECT (or of its LINK index) as a list."
  (coerce (with-live-object (object 'object-color)
            (native:object-color (whandle object) (object-handle object) (or link -1)))
          'list))

(defun link-colors (object)
  "The RGBA colour of every link of the articulated OBJECT, as OBJECT-COLOR gives each: a
simple vector of lists, indexed by link index."
  (let ((v (with-live-object (object 'link-colors)
             (native:robot-link-colors (whandle object) (object-handle object)))))
    (coerce (loop for i from 0 below (length v) by 4
                  collect (list (aref v i) (aref v (+ i 1)) (aref v (+ i 2)) (aref v (+ i 3))))
            'simple-vector)))

;;; ---- object kinds -----------------------------------------------------------------------------

(defvar *object-kinds* (make-hash-table :test 'eq)
  "Object kind keyword → (keys . constructor).")

(defparameter *common-keys* '(:collision-group :collision-mask :color :types)
  "Keys every object kind accepts.")

(defmacro define-object-kind (kind (world pose &rest keys) &body body)
  "Define how ADD-OBJECT makes objects of KIND. KEYS are &key parameters (with defaults);
BODY returns (values native-handle object-class [types]). Keys not listed (nor common: collision
group and mask, color, types) are rejected by ADD-OBJECT with an error naming them."
  (let ((key-names (mapcar (lambda (k) (intern (string (if (consp k) (first k) k)) :keyword)) keys)))
    `(setf (gethash ,kind *object-kinds*)
           (cons ',key-names
                 (lambda (,world ,pose &key ,@keys &allow-other-keys)
                   (declare (ignorable ,world ,pose))
                   ,@body)))))

(defun object-kind-keys (kind)
  "The keys ADD-OBJECT accepts for KIND."
  (append (car (gethash kind *object-kinds*)) *common-keys*))

(defgeneric add-object (world type name pose &rest keys)
  (:documentation "Add an object of TYPE (:static-plane :box :colored-box :sphere :cylinder :cone
:mesh :urdf :point-cloud ...) called NAME at POSE to WORLD and return it. KEYS is a list of
keywords and values; unknown keys are an error. :TYPES is a list of item types (symbols, or
strings, which become keywords). :COMPOUND of :mesh objects (default
*ALL-MESHES-AS-COMPOUND*) and of :urdf objects (default NIL) chooses between one convex hull per
sub-mesh of a mesh file (true) and one hull over the whole mesh (NIL)."))

(defmethod add-object (world type name pose &rest keys)
  (declare (ignore type name pose keys))
  (check-world world 'add-object))

(defun normalize-item-types (types)
  "The :TYPES argument of ADD-OBJECT, a list, as a list of symbols; strings become keywords."
  (unless (and (listp types) (alexandria:proper-list-p types))
    (btr-fail "ADD-OBJECT: :types ~s, expected a list of item types, e.g. (:bottle)" types))
  (flet ((one (x)
           (cond ((and x (symbolp x)) x)
                 ((and (stringp x) (plusp (length x))) (intern (string-upcase x) :keyword))
                 (t (btr-fail "ADD-OBJECT: item type ~s in :types ~s, expected a symbol or string"
                              x types)))))
    (mapcar #'one types)))

(defmethod add-object ((world bt-reasoning-world) type name pose &rest keys)
  (check-world world 'add-object)
  (unless (evenp (length keys))
    (btr-fail "ADD-OBJECT ~s: odd number of keyword arguments ~s, expected :key value pairs" name keys))
  (loop for k in keys by #'cddr
        unless (keywordp k)
          do (btr-fail "ADD-OBJECT ~s: ~s in ~s is not a keyword, expected :key value pairs" name k keys))
  (when (getf keys :types)
    (setf keys (copy-list keys))
    (setf (getf keys :types) (normalize-item-types (getf keys :types))))
  (let ((entry (gethash type *object-kinds*)))
    (unless entry
      (btr-fail "ADD-OBJECT: object type ~s is unknown, expected one of ~{~s~^ ~}"
                type (sort (loop for k being the hash-keys of *object-kinds* collect k) #'string<)))
    (unless (and name (symbolp name))
      (btr-fail "ADD-OBJECT: name ~s, expected a non-NIL symbol" name))
    (when (object world name)
      (btr-fail "ADD-OBJECT: an object called ~s already exists" name))
    (unless (evenp (length keys))
      (btr-fail "ADD-OBJECT: odd number of keyword arguments ~s" keys))
    (loop for (k v) on keys by #'cddr
          unless (member k (object-kind-keys type))
            do (btr-fail "ADD-OBJECT: key ~s is unknown for type ~s, expected one of ~{~s~^ ~}"
                         k type (object-kind-keys type)))
    (let ((pose-vec (pose->vector (or pose '((0 0 0) (0 0 0 1))) (format nil "pose of ~s" name))))
      (with-world-lock (world)
        (multiple-value-bind (handle class types extra-slots)
            (apply (cdr entry) world pose-vec keys)
          (let ((object (apply #'make-instance class :name name :world world :handle handle
                               :kind type :types (or (getf keys :types) types) :spec keys
                               extra-slots)))
            (handler-bind ((error (lambda (e) (declare (ignore e))
                                    (ignore-errors (native:remove-object (world-handle world) handle)))))
              (apply-common-keys object keys))
            (%register-object world object)))))))

(defun apply-common-keys (object keys)
  (let ((w (whandle object)) (h (object-handle object)))
    (destructuring-bind (&key collision-group collision-mask color &allow-other-keys) keys
      (when (or collision-group collision-mask)
        (multiple-value-bind (group mask) (native:object-collision-filter w h)
          (native:set-object-collision-filter
           w h
           (if collision-group (collision-group-bits collision-group) group)
           (if collision-mask (collision-group-bits collision-mask) mask))))
      (when color
        (native:set-object-color w h (color-rgba color) -1)))))

(defun call-without-collisions (object thunk)
  "Call THUNK while OBJECT (all its links) collides with nothing in its world's physics (its
collision mask cleared), then restore its collision filter. Contact queries made meanwhile
see no contact of OBJECT either."
  (unless (typep object 'object)
    (btr-fail "CALL-WITHOUT-COLLISIONS: ~s is not an object of a reasoning world" object))
  (let ((w (whandle object)) (h (object-handle object)))
    (multiple-value-bind (group mask) (with-live-object (object 'call-without-collisions)
                                        (native:object-collision-filter w h))
      (native:set-object-collision-filter w h group 0)
      (unwind-protect (funcall thunk)
        (when (native:world-alive-p w)
          (ignore-errors (native:set-object-collision-filter w h group mask)))))))

(defun color-rgba (color)
  "COLOR (r g b) or (r g b a), components in [0, 1], as a list of four doubles."
  (unless (and (listp color) (<= 3 (length color) 4) (every #'realp color))
    (btr-fail "color ~s, expected (r g b) or (r g b a) with components in [0, 1]" color))
  (mapcar (lambda (c) (coerce c 'double-float)) (if (= (length color) 3) (append color '(1)) color)))

(defun remove-object (world name)
  "Remove the object NAME from WORLD (detaching whatever is attached to it)."
  (let ((o (object-or-fail world name)))
    (with-world-lock (world)
      (dolist (other (objects world))
        (when (typep other 'robot-object)
          (setf (%attached other) (remove name (%attached other) :key #'first))))
      (native:remove-object (world-handle world) (object-handle o))
      (%unregister-object world name)
      t)))

;;; ---- primitive kinds ----------------------------------------------------------------------------

(defun mass-arg (mass what)
  (unless (and (finite-real-p mass) (>= mass 0) (<= mass *max-mass*))
    (btr-fail "~a: mass ~s, expected a real from 0 to ~g kg (BTR::*MAX-MASS*)" what mass *max-mass*))
  (coerce mass 'double-float))

(defun size-arg (size what)
  (unless (and (listp size) (= (length size) 3)
               (every (lambda (s) (and (finite-real-p s) (> s 0) (<= s *max-size*))) size))
    (btr-fail "~a: size ~s, expected (x y z) with positive reals of at most ~g m (BTR::*MAX-SIZE*)"
              what size *max-size*))
  (mapcar (lambda (s) (coerce s 'double-float)) size))

(defun positive-arg (x what)
  (unless (and (finite-real-p x) (> x 0) (<= x *max-size*))
    (btr-fail "~a is ~s, expected a positive real of at most ~g m (BTR::*MAX-SIZE*)" what x *max-size*))
  (coerce x 'double-float))

(define-object-kind :static-plane (world pose (normal '(0 0 1)) (constant 0))
  (unless (and (listp normal) (= 3 (length normal)) (every #'realp normal))
    (btr-fail ":static-plane normal ~s, expected (x y z)" normal))
  (values (native:add-plane (world-handle world) :normal normal :constant constant) 'object '(:floor)))

(define-object-kind :box (world pose (mass 0) (size '(0.1 0.1 0.1)))
  (values (native:add-box (world-handle world) pose (size-arg size ":box") :mass (mass-arg mass ":box"))
          'item '(:box)))

(setf (gethash :colored-box *object-kinds*) (gethash :box *object-kinds*))

(define-object-kind :sphere (world pose (mass 0) (radius 0.05))
  (values (native:add-sphere (world-handle world) pose (positive-arg radius ":sphere radius")
                             :mass (mass-arg mass ":sphere"))
          'item '(:sphere)))

(define-object-kind :cylinder (world pose (mass 0) (size '(0.1 0.1 0.1)))
  (let ((s (size-arg size ":cylinder")))
    (values (native:add-cylinder (world-handle world) pose (/ (first s) 2) (third s)
                                 :mass (mass-arg mass ":cylinder"))
            'item '(:cylinder))))

(define-object-kind :cone (world pose (mass 0) (radius 0.05) (height 0.1))
  (values (native:add-cone (world-handle world) pose (positive-arg radius ":cone radius")
                           (positive-arg height ":cone height") :mass (mass-arg mass ":cone"))
          'item '(:cone)))

(defun spanning-points-p (points)
  "True when the (x y z) POINTS do not all lie on one line (they span at least a plane)."
  (let* ((vectors (mapcar (lambda (p) (mapcar (lambda (c) (coerce c 'double-float)) p)) points))
         (p0 (first vectors))
         (p1 (find-if (lambda (p) (> (reduce #'+ (mapcar (lambda (a b) (expt (- a b) 2)) p p0))
                                     1d-18))
                      vectors)))
    (flet ((minus (a b) (mapcar #'- a b)))
      (and p1
           (let ((d1 (minus p1 p0)))
             (some (lambda (p)
                     (destructuring-bind (ax ay az) d1
                       (destructuring-bind (bx by bz) (minus p p0)
                         (> (+ (expt (- (* ay bz) (* az by)) 2) (expt (- (* az bx) (* ax bz)) 2)
                               (expt (- (* ax by) (* ay bx)) 2))
                            1d-18))))
                   vectors))))))

(define-object-kind :point-cloud (world pose points)
  (unless (and (listp points) (>= (length points) 4))
    (btr-fail ":point-cloud points ~s, expected a list of at least 4 (x y z) points" points))
  (unless (every (lambda (p) (and (listp p) (= (length p) 3) (every #'realp p))) points)
    (btr-fail ":point-cloud points ~s, expected (x y z) lists of reals" points))
  (unless (spanning-points-p points)
    (btr-fail ":point-cloud points ~s all lie on one line (or are one point); a convex hull ~
               needs points spanning at least a plane" points))
  (values (native:add-convex-hull (world-handle world) pose points) 'item '(:point-cloud)))
