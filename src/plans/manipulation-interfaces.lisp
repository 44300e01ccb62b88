;;;; CRAM-MANIPULATION-INTERFACES (MAN-INT): what plans ask about objects they manipulate —
;;;; the grasps an object type offers, the gripper poses of a grasp, gripper opening and
;;;; effort — and the trajectory segments of picking up and placing.
;;;; CRAM-OBJECT-KNOWLEDGE (OBJECTS) fills these tables for household objects.

(defpackage :cram-manipulation-interfaces
  (:nicknames :man-int)
  (:use :cl)
  (:export
   ;; object types
   #:object-type-direct-subtype #:object-type-subtype-p #:object-type-supertypes
   #:define-object-type #:known-object-types
   ;; grasps
   #:def-object-type-to-gripper-transforms #:grasp-spec #:get-action-grasps
   #:object-type-grasps #:get-object-type-grasps #:get-object-type-to-gripper-transform
   #:get-object-type-to-gripper-pregrasp-transforms
   #:get-object-type-to-gripper-lift-offsets
   #:get-object-type-gripping-effort #:get-object-type-gripper-opening
   #:define-object-type-gripping #:object-rotationally-symmetric-p
   #:manipulation-knowledge-error
   #:get-object-type-lift-offsets #:get-object-type-carry-config #:define-object-type-carry-config
   #:grasp-location-variant-p
   ;; object knowledge in context (generics, methods in CRAM-OBJECT-KNOWLEDGE)
   #:get-object-likely-location #:get-object-destination #:get-object-location-type
   #:most-specific-type-method #:no-object-knowledge #:requested-object-type
   ;; containers (defined by cram-urdf-environment-manipulation)
   #:get-container-opening-distance #:object-is-a-container
   ;; trajectories
   #:traj-segment #:make-traj-segment #:traj-segment-label #:traj-segment-poses
   #:get-action-trajectory #:get-traj-poses-by-label
   ;; where an object is (occasions of the household plans)
   #:location-certain
   #:grasp-pose #:transform-pose-by))

(in-package :cram-manipulation-interfaces)

(define-condition manipulation-knowledge-error (simple-error) ()
  (:documentation "Bad input to, or missing knowledge behind, a manipulation interface call."))

(defun knowledge-error (control &rest arguments)
  (error 'manipulation-knowledge-error :format-control control :format-arguments arguments))

;;; ---- object types --------------------------------------------------------------------------

(defvar *object-type-parents* (make-hash-table :test 'eq)
  "Object type keyword -> list of its direct supertypes.")

(defmacro define-object-type (type &rest supertypes)
  "Declare the object type TYPE (a keyword) with its direct SUPERTYPES (keywords)."
  (check-type type keyword)
  (dolist (s supertypes) (check-type s keyword))
  `(progn (setf (gethash ,type *object-type-parents*) ',supertypes) ,type))

(defun known-object-types ()
  "Every declared object type, sorted."
  (sort (loop for k being the hash-keys of *object-type-parents* collect k) #'string<))

(defun object-type-direct-subtype (type subtype)
  "True when SUBTYPE was declared with TYPE as a direct supertype."
  (and (member type (gethash subtype *object-type-parents*)) t))

(defun object-type-supertypes (type)
  "TYPE followed by all its supertypes, nearest first."
  (let ((result '()) (queue (list type)))
    (loop while queue
          do (let ((next (pop queue)))
               (unless (member next result)
                 (push next result)
                 (setf queue (append queue (gethash next *object-type-parents*))))))
    (nreverse result)))

(defun object-type-subtype-p (type subtype)
  "True when SUBTYPE is TYPE or one of its (transitive) subtypes."
  (and (member type (object-type-supertypes subtype)) t))

;;; ---- gripping knowledge ----------------------------------------------------------------------

(defstruct (gripping (:constructor make-gripping (effort opening symmetric)))
  effort opening symmetric)

(defvar *gripping* (make-hash-table :test 'eq)
  "Object type -> GRIPPING (effort, opening in metres, rotational symmetry about z).")

(defmacro define-object-type-gripping (type &key (effort 50) (opening 0.1) rotationally-symmetric)
  "Declare how to grip objects of TYPE: the gripping EFFORT, the gripper OPENING (metres) and
whether the object looks the same after any rotation about its z axis."
  (check-type type keyword)
  `(progn (setf (gethash ,type *gripping*)
                (make-gripping ,effort ,opening ,rotationally-symmetric))
          ,type))

(defun lookup-inherited (table type what)
  (or (some (lambda (x) (gethash x table)) (object-type-supertypes type))
      (knowledge-error "No ~a known for the object type ~s (known types: ~{~s~^, ~})."
                       what type (known-object-types))))

(defun check-type-keyword (type what)
  (unless (keywordp type)
    (knowledge-error "~a: expected an object type keyword such as :BOTTLE, got ~s." what type)))

(defun get-object-type-gripping-effort (object-type)
  "The gripping effort for objects of OBJECT-TYPE (inherited from supertypes)."
  (check-type-keyword object-type 'get-object-type-gripping-effort)
  (gripping-effort (lookup-inherited *gripping* object-type "gripping effort")))

(defun get-object-type-gripper-opening (object-type)
  "The gripper opening (metres) before grasping objects of OBJECT-TYPE."
  (check-type-keyword object-type 'get-object-type-gripper-opening)
  (gripping-opening (lookup-inherited *gripping* object-type "gripper opening")))

(defun object-rotationally-symmetric-p (object-type)
  "True when objects of OBJECT-TYPE look the same after any rotation about their z axis."
  (check-type-keyword object-type 'object-rotationally-symmetric-p)
  (let ((g (some (lambda (x) (gethash x *gripping*)) (object-type-supertypes object-type))))
    (and g (gripping-symmetric g))))

;;; ---- grasps ----------------------------------------------------------------------------------

;; A grasp either derives its two pregrasp poses and its lift from the approach direction
;; (PREGRASP-BACK, PREGRASP-UP, LIFT), or states them as CRAM does: two PREGRASP-OFFSETS in the
;; object frame and a LIFT-OFFSET in the robot base frame.
(defstruct (grasp-spec (:constructor %make-grasp-spec))
  "One grasp of an object type: the TCP pose in the object frame, the approach direction
(unit vector in the object frame along which the gripper moves onto the object), the arms
that may use it, the pregrasp offsets and the lift height; or, when PREGRASP-OFFSETS is set,
the two pregrasp offsets (object frame) and the LIFT-OFFSET vector (base frame)."
  grasp arms translation rotation approach
  (pregrasp-back 0.15d0) (pregrasp-up 0.07d0) (lift 0.07d0)
  pregrasp-offsets lift-offset)

(setf (documentation 'grasp-spec-lift-offset 'function)
      "NIL, or the two lift offsets (3D vectors, base frame) from the grasp pose.")

(defvar *grasps* (make-hash-table :test 'eq)
  "Object type -> list of GRASP-SPEC in preference order.")

(defvar *grasp-location-variants* (make-hash-table :test 'eq)
  "Object type -> list of (location-type grasp pregrasp-offsets lift-offset): the pregrasp and
lift of GRASP when the object lies in or on an object of LOCATION-TYPE.")

(defun d (x) (coerce x 'double-float))

(defun vec (list)
  (destructuring-bind (x y z) list (cl-transforms:make-3d-vector (d x) (d y) (d z))))

(defun real-triple-p (x) (and (listp x) (= 3 (length x)) (every #'realp x)))

(defmacro def-object-type-to-gripper-transforms (object-types arms grasp
                                                 &key grasp-translation grasp-rotation
                                                   approach (pregrasp-back 0.15)
                                                   (pregrasp-up 0.07) (lift 0.07)
                                                   pregrasp-offsets lift-offset location-type)
  "Declare the GRASP (a keyword such as :LEFT-SIDE) of OBJECT-TYPES (a keyword or a list) for
ARMS (a list of arm keywords, or :ALL). GRASP-TRANSLATION (x y z) and GRASP-ROTATION (a
quaternion (x y z w), or a rotation matrix as three rows ((r11 r12 r13) (r21 r22 r23) (r31
r32 r33))) give the tool frame in the object frame. Either APPROACH (x y z), the direction in
the object frame along which the gripper moves onto the object, with pregrasp poses
PREGRASP-BACK metres back against it (the first also PREGRASP-UP higher) and two lifts by LIFT
metres; or PREGRASP-OFFSETS ((x y z) [(x y z)]), the two pregrasp poses as offsets of the
grasp pose in the object frame (one offset: both equal), and LIFT-OFFSET (x y z), the first
lift in the robot base frame (the second lifts as far again), or ((x y z) (x y z)), the first
lift and the second one on top of it. With LOCATION-TYPE (a keyword
such as :DRAWER) only PREGRASP-OFFSETS and LIFT-OFFSET are declared, for objects lying in or
on an object of that type."
  (let ((types (if (listp object-types) object-types (list object-types))))
    (dolist (type types) (check-type type keyword))
    (check-type grasp keyword)
    (check-type location-type (or null keyword))
    `(progn
       ,@(loop for type in types
               collect (if location-type
                           `(register-grasp-location-variant ,type ,location-type ,grasp
                                                             ',pregrasp-offsets ',lift-offset)
                           `(register-grasp ,type ,grasp ',arms ',grasp-translation ',grasp-rotation
                                            ',approach ,pregrasp-back ,pregrasp-up ,lift
                                            ',pregrasp-offsets ',lift-offset)))
       ',grasp)))

(defun parse-rotation (rotation type grasp)
  "The quaternion of ROTATION: a quaternion list (x y z w) or three matrix rows."
  (cond ((and (listp rotation) (= 4 (length rotation)) (every #'realp rotation))
         (cl-transforms:normalize (apply #'cl-transforms:make-quaternion (mapcar #'d rotation))))
        ((and (listp rotation) (= 3 (length rotation)) (every #'real-triple-p rotation))
         (handler-case
             (cl-transforms:matrix->quaternion
              (make-array '(3 3) :initial-contents (mapcar (lambda (row) (mapcar #'d row)) rotation)))
           (error ()
             (knowledge-error "Grasp ~s of ~s: the rotation matrix ~s is not a rotation ~
                               (orthonormal rows, determinant +1)." grasp type rotation))))
        (t (knowledge-error "Grasp ~s of ~s: expected a quaternion (x y z w) or a rotation matrix ~
                             ((r11 r12 r13) (r21 r22 r23) (r31 r32 r33)), got ~s."
                            grasp type rotation))))

(defun parse-pregrasp-offsets (offsets type grasp)
  "Two 3D vectors from OFFSETS, a list of one or two (x y z); NIL for NIL."
  (when offsets
    (unless (and (listp offsets) (<= 1 (length offsets) 2) (every #'real-triple-p offsets))
      (knowledge-error "Grasp ~s of ~s: expected pregrasp offsets ((x y z) [(x y z)]), got ~s."
                       grasp type offsets))
    (let ((vs (mapcar #'vec offsets)))
      (list (first vs) (or (second vs) (first vs))))))

(defun lift-pair (v)
  "The two lift offsets of a lift by V: V and twice V."
  (list v (cl-transforms:v* v 2d0)))

(defun parse-lift-offset (offset type grasp)
  "The two lift offsets (from the grasp pose) of OFFSET: (x y z), a lift by it and then by it
again, or ((x y z) (x y z)), a lift by the first and then by the second."
  (cond ((null offset) nil)
        ((real-triple-p offset) (lift-pair (vec offset)))
        ((and (listp offset) (= 2 (length offset)) (every #'real-triple-p offset))
         (let ((first (vec (first offset))))
           (list first (cl-transforms:v+ first (vec (second offset))))))
        (t (knowledge-error "Grasp ~s of ~s: expected a lift offset (x y z) or two ((x y z) ~
                             (x y z)), got ~s." grasp type offset))))

(defun approach-from-offsets (offsets)
  "The unit approach direction towards the grasp from the last pregrasp offset that is not 0."
  (let ((v (find-if (lambda (v) (> (cl-transforms:v-norm v) 1d-9)) (reverse offsets))))
    (if v
        (cl-transforms:normalize-vector (cl-transforms:v* v -1d0))
        (cl-transforms:make-3d-vector 0 0 -1))))

(defun register-grasp (type grasp arms translation rotation approach back up lift
                       &optional pregrasp-offsets lift-offset)
  (unless (real-triple-p translation)
    (knowledge-error "Grasp ~s of ~s: expected a translation (x y z), got ~s." grasp type translation))
  (let ((offsets (parse-pregrasp-offsets pregrasp-offsets type grasp))
        (lift-vector (parse-lift-offset lift-offset type grasp)))
    (unless (or offsets (real-triple-p approach))
      (knowledge-error "Grasp ~s of ~s: expected an approach direction (x y z) or pregrasp ~
                        offsets, got ~s." grasp type approach))
    (when (and approach (not (real-triple-p approach)))
      (knowledge-error "Grasp ~s of ~s: expected an approach direction (x y z), got ~s." grasp type approach))
    (let ((spec (%make-grasp-spec
                 :grasp grasp :arms arms :translation (vec translation)
                 :rotation (parse-rotation rotation type grasp)
                 :approach (if approach
                               (cl-transforms:normalize-vector (vec approach))
                               (approach-from-offsets offsets))
                 :pregrasp-back (d back) :pregrasp-up (d up) :lift (d lift)
                 :pregrasp-offsets offsets
                 :lift-offset (or lift-vector
                                  (and offsets (lift-pair (cl-transforms:make-3d-vector 0 0 (d lift))))))))
      (setf (gethash type *grasps*)
            (append (remove grasp (gethash type *grasps*) :key #'grasp-spec-grasp)
                    (list spec)))
      grasp)))

(defun register-grasp-location-variant (type location-type grasp pregrasp-offsets lift-offset)
  (let ((offsets (parse-pregrasp-offsets pregrasp-offsets type grasp))
        (lift-vector (parse-lift-offset lift-offset type grasp)))
    (unless (and offsets lift-vector)
      (knowledge-error "Grasp ~s of ~s in a ~s: a location-type variant needs both pregrasp ~
                        offsets and a lift offset." grasp type location-type))
    (setf (gethash type *grasp-location-variants*)
          (cons (list location-type grasp offsets lift-vector)
                (remove-if (lambda (e) (and (eq (first e) location-type) (eq (second e) grasp)))
                           (gethash type *grasp-location-variants*))))
    grasp))

(defun grasp-location-variant (object-type grasp location-type)
  "(pregrasp-offsets lift-offset) of GRASP of OBJECT-TYPE for a LOCATION-TYPE, or NIL: the
variant of the nearest supertype of OBJECT-TYPE declared for LOCATION-TYPE or a supertype."
  (when location-type
    (let ((location-types (object-type-supertypes location-type)))
      (loop for type in (object-type-supertypes object-type)
            for entry = (loop for lt in location-types
                              thereis (find-if (lambda (e) (and (eq (first e) lt) (eq (second e) grasp)))
                                               (gethash type *grasp-location-variants*)))
            when entry return (cddr entry)))))

(defun grasp-location-variant-p (object-type grasp location-type)
  "True when GRASP of OBJECT-TYPE has its own pregrasp and lift for objects in or on an object
of LOCATION-TYPE (or of a subtype of a type declared so)."
  (and (grasp-location-variant object-type grasp location-type) t))

(defun type-grasp-specs (object-type)
  (or (some (lambda (x) (gethash x *grasps*)) (object-type-supertypes object-type))
      (knowledge-error "No grasps known for the object type ~s (types with grasps: ~{~s~^, ~})."
                       object-type
                       (sort (loop for k being the hash-keys of *grasps* collect k) #'string<))))

(defun object-type-grasps (object-type &optional arm)
  "The grasp keywords OBJECT-TYPE offers (for ARM, when given), in preference order."
  (check-type-keyword object-type 'object-type-grasps)
  (loop for spec in (type-grasp-specs object-type)
        when (or (null arm) (eq (grasp-spec-arms spec) :all) (member arm (grasp-spec-arms spec)))
          collect (grasp-spec-grasp spec)))

(defun get-object-type-grasps (object-type facing-robot-face bottom-face rotationally-symmetric-p arm)
  "CRAM's call for the grasps OBJECT-TYPE offers ARM, in preference order (as
OBJECT-TYPE-GRASPS). CRAM narrows the choice by the object's face towards the robot, its bottom
face and its rotational symmetry; object faces are not modelled here, so those three must be
NIL (as the tutorials pass them)."
  (when (or facing-robot-face bottom-face rotationally-symmetric-p)
    (knowledge-error "GET-OBJECT-TYPE-GRASPS: object faces are not modelled; pass NIL for the ~
facing-robot face (~s), the bottom face (~s) and the symmetry flag (~s), or use GET-ACTION-GRASPS ~
with the object's transform in the robot base."
                     facing-robot-face bottom-face rotationally-symmetric-p))
  (object-type-grasps object-type arm))

(defun find-grasp-spec (object-type grasp)
  (check-type-keyword object-type 'find-grasp-spec)
  (or (find grasp (type-grasp-specs object-type) :key #'grasp-spec-grasp)
      (knowledge-error "The object type ~s has no grasp ~s: expected one of ~{~s~^, ~}."
                       object-type grasp (object-type-grasps object-type))))

(defun get-action-grasps (object-type arm &optional object-transform-in-base)
  "The grasps to try for OBJECT-TYPE with ARM. With OBJECT-TRANSFORM-IN-BASE (the object's
pose relative to the robot base, a transform or pose) grasps whose gripper would point
towards the robot come last, the others ordered by how well they face away from the robot."
  (let ((grasps (object-type-grasps object-type arm)))
    (if (null object-transform-in-base)
        grasps
        (let* ((q (cl-transforms:rotation (ensure-transform object-transform-in-base)))
               (scored (loop for g in grasps
                             for spec = (find-grasp-spec object-type g)
                             for a = (cl-transforms:rotate q (grasp-spec-approach spec))
                             ;; approach along +x of the base: pushing away from the robot
                             collect (cons g (cl-transforms:x a)))))
          (mapcar #'car (stable-sort scored #'> :key #'cdr))))))

(defun ensure-transform (x)
  (etypecase x
    (cl-transforms:transform x)
    (cl-transforms:pose (cl-transforms:pose->transform x))))

(defun get-object-type-to-gripper-transform (object-type object-name arm grasp)
  "The tool frame of ARM grasping an OBJECT-TYPE object with GRASP, as a transform in the
object frame. OBJECT-NAME is accepted for per-object knowledge and not used otherwise."
  (declare (ignore object-name arm))
  (let ((spec (find-grasp-spec object-type grasp)))
    (cl-transforms:make-transform (grasp-spec-translation spec) (grasp-spec-rotation spec))))

(defun get-object-type-to-gripper-pregrasp-transforms (object-type object-name arm grasp
                                                       &optional grasp-transform location-type)
  "The two pregrasp tool frames (object frame) of GRASP: its declared pregrasp offsets (those
of LOCATION-TYPE, the type of the object the object lies in or on, when it has its own), or
back against the approach and up, then back at the grasp height."
  (let* ((spec (find-grasp-spec object-type grasp))
         (g (or grasp-transform
                (get-object-type-to-gripper-transform object-type object-name arm grasp)))
         (offsets (or (first (grasp-location-variant object-type grasp location-type))
                      (grasp-spec-pregrasp-offsets spec))))
    (if offsets
        (mapcar (lambda (o) (offset-transform g o)) offsets)
        (let ((back (cl-transforms:v* (grasp-spec-approach spec) (- (grasp-spec-pregrasp-back spec))))
              (up (cl-transforms:make-3d-vector 0 0 (grasp-spec-pregrasp-up spec))))
          (list (offset-transform g (cl-transforms:v+ back up))
                (offset-transform g back))))))

(defun get-object-type-lift-offsets (object-type grasp &optional location-type)
  "The offsets (3D vectors, robot base frame) of the two lift poses from the grasp pose of
GRASP on an OBJECT-TYPE object lying in or on an object of LOCATION-TYPE: the lift offset and
twice it, or the first lift and the first plus the second where two were declared."
  (let ((spec (find-grasp-spec object-type grasp)))
    (or (second (grasp-location-variant object-type grasp location-type))
        (grasp-spec-lift-offset spec)
        (lift-pair (cl-transforms:make-3d-vector 0 0 (grasp-spec-lift spec))))))

(defun get-object-type-to-gripper-lift-offsets (object-type grasp &optional location-type)
  "The heights (metres, world z) of the two lift poses above the grasp pose."
  (mapcar #'cl-transforms:z (get-object-type-lift-offsets object-type grasp location-type)))

(defun offset-transform (transform offset)
  (cl-transforms:make-transform (cl-transforms:v+ (cl-transforms:translation transform) offset)
                                (cl-transforms:rotation transform)))

;;; ---- trajectories ----------------------------------------------------------------------------

(defstruct (traj-segment (:constructor make-traj-segment (label poses)))
  "A labelled list of tool-frame poses (in the fixed frame) an arm moves through."
  label poses)

(defun transform-pose-by (pose transform)
  "POSE (the object's pose in the fixed frame) composed with TRANSFORM (in the object frame):
the resulting pose in the fixed frame."
  (cl-transforms:transform->pose
   (cl-transforms:transform* (cl-transforms:pose->transform pose) transform)))

(defun grasp-pose (object-type object-pose arm grasp)
  "The tool frame pose (fixed frame) for grasping an OBJECT-TYPE object at OBJECT-POSE."
  (transform-pose-by object-pose (get-object-type-to-gripper-transform object-type nil arm grasp)))

(defun shift-pose (pose offset)
  (cl-transforms:make-pose (cl-transforms:v+ (cl-transforms:origin pose) offset)
                           (cl-transforms:orientation pose)))

(defun get-action-trajectory (action-type arm grasp object-type object-pose
                              &key object-to-gripper location-type)
  "The trajectory segments of ACTION-TYPE (:PICKING-UP or :PLACING) for ARM with GRASP on an
OBJECT-TYPE object whose pose (fixed frame) is OBJECT-POSE — for placing, the pose the
object shall have. OBJECT-TO-GRIPPER (a transform in the object frame) replaces the grasp
knowledge, e.g. the actual hold of an object in hand. LOCATION-TYPE, the type of the object
it lies in or on (e.g. :DRAWER), chooses that location's pregrasp and lift when declared.
Picking up: :REACHING (two pregrasp poses), :GRASPING, :LIFTING (two poses).
Placing: :REACHING (the lift poses from above), :PUTTING, :RETRACTING (pregrasp poses)."
  (let* ((g (or object-to-gripper
                (get-object-type-to-gripper-transform object-type nil arm grasp)))
         (grasp-pose (transform-pose-by object-pose g))
         (pregrasps (mapcar (lambda (tr) (transform-pose-by object-pose tr))
                            (get-object-type-to-gripper-pregrasp-transforms
                             object-type nil arm grasp g location-type)))
         (lifts (mapcar (lambda (v) (shift-pose grasp-pose v))
                        (get-object-type-lift-offsets object-type grasp location-type))))
    (ecase action-type
      (:picking-up (list (make-traj-segment :reaching pregrasps)
                         (make-traj-segment :grasping (list grasp-pose))
                         (make-traj-segment :lifting lifts)))
      (:placing (list (make-traj-segment :reaching (reverse lifts))
                      (make-traj-segment :putting (list grasp-pose))
                      (make-traj-segment :retracting (reverse pregrasps)))))))

;;; ---- carrying ----------------------------------------------------------------------------------

(defvar *carry-configs* (make-hash-table :test 'eq)
  "Object type -> list of (grasps . arm configuration); GRASPS NIL means every grasp.")

(defmacro define-object-type-carry-config (type configuration &key grasps)
  "Declare that objects of TYPE are carried with the arms in CONFIGURATION (a keyword such as
:CARRY-TOP, a robot-joint-states configuration), after any grasp or only after GRASPS."
  (check-type type keyword)
  (check-type configuration keyword)
  `(progn (setf (gethash ,type *carry-configs*)
                (cons (cons ',grasps ,configuration)
                      (remove ',grasps (gethash ,type *carry-configs*) :key #'car :test #'equal)))
          ,type))

(defun get-object-type-carry-config (object-type grasp)
  "The arm configuration (:CARRY unless declared otherwise) for carrying an OBJECT-TYPE object
held with GRASP: the declaration of the nearest supertype that covers GRASP."
  (check-type-keyword object-type 'get-object-type-carry-config)
  (or (loop for type in (object-type-supertypes object-type)
            thereis (loop for (grasps . config) in (gethash type *carry-configs*)
                          when (or (null grasps) (member grasp grasps)) return config))
      :carry))

(defun get-traj-poses-by-label (trajectory label)
  "The poses of the segment LABEL of TRAJECTORY (a list of TRAJ-SEGMENT)."
  (let ((segment (find label trajectory :key #'traj-segment-label)))
    (unless segment
      (knowledge-error "The trajectory has no segment ~s: it has ~{~s~^, ~}."
                       label (mapcar #'traj-segment-label trajectory)))
    (traj-segment-poses segment)))
