;;;; Articulated objects from URDF (robots and environments): joints, links, rigid bodies named
;;;; OBJ.LINK, attachments.

(in-package :cram-bullet-reasoning)

(defstruct (kinematic-model (:conc-name km-))
  "What does not change between copies of an articulated object. Joint names are the URDF
model's own strings (the IK chains' too), found by identity before they are hashed."
  (urdf nil) (link-names #() :type simple-vector) (link-index (make-hash-table :test 'equal))
  (joint-names #() :type simple-vector) (joint-index (make-hash-table :test 'equal))
  (joint-index-eq (make-hash-table :test 'eq))
  (joint-info #() :type simple-vector) (rigid-bodies '())
  ;; per joint: limited (revolute or prismatic with lower < upper) and its limits
  (limited (make-array 0 :element-type 'bit) :type simple-bit-vector)
  (lower (make-array 0 :element-type 'double-float) :type (simple-array double-float (*)))
  (upper (make-array 0 :element-type 'double-float) :type (simple-array double-float (*))))

(defclass robot-object (object)
  ((model :initarg :model :reader %model)
   (attached :initform '() :accessor %attached
             :documentation "List of (object-name link-name loose grasp)."))
  (:documentation "An articulated object built from a URDF: a robot or an environment."))

(defun robot-object-p (object) "True for articulated objects." (typep object 'robot-object))

(defmethod %model ((x t))
  (btr-fail "~a is not an articulated object (a robot or other URDF object): it has no links or joints"
            (if (typep x 'object) (format nil "object ~s" (name x)) (format nil "~s" x))))

(defun urdf (robot) "The CL-URDF:ROBOT model of ROBOT." (km-urdf (%model robot)))

(defun link-names (robot) "The link names of ROBOT (URDF order)." (coerce (km-link-names (%model robot)) 'list))

(defun link-count (object)
  "The number of links of the articulated OBJECT."
  (unless (typep object 'robot-object)
    (btr-fail "LINK-COUNT: ~s is not an articulated object" object))
  (length (km-link-names (%model object))))

(defun joint-names (robot)
  "The movable joint names of ROBOT (revolute, continuous, prismatic; URDF order)."
  (loop for n across (km-joint-names (%model robot))
        for info across (km-joint-info (%model robot))
        when (member (getf info :type) '(:revolute :continuous :prismatic)) collect n))

(defun link-index (robot link)
  "Index of LINK (a name) in ROBOT; an error naming both when unknown."
  (or (gethash link (km-link-index (%model robot)))
      (btr-fail "link ~s is not a link of ~s (~d links, e.g. ~{~s~^ ~})" link (name robot)
                (length (km-link-names (%model robot)))
                (coerce (subseq (km-link-names (%model robot)) 0 (min 5 (length (km-link-names (%model robot))))) 'list))))

(defun link-exists-p (robot link) "True when ROBOT has a link LINK." (and (gethash link (km-link-index (%model robot))) t))

(defun model-joint-index (model joint)
  "Index of JOINT (a name) in the kinematic MODEL, or NIL."
  (or (gethash joint (km-joint-index-eq model))
      (gethash joint (km-joint-index model))))

(defun joint-index (robot joint)
  "Index of JOINT (a name) in ROBOT; an error naming both when unknown."
  (or (model-joint-index (%model robot) joint)
      (btr-fail "joint ~s is not a joint of ~s" joint (name robot))))

(defun link-pose (robot link)
  "The world pose of LINK (a name) of ROBOT."
  (vector->pose (native:robot-link-pose (whandle robot) (object-handle robot) (link-index robot link))))

(defun joint-state (robot joint)
  "The position of JOINT (a name) of ROBOT."
  (native:robot-joint (whandle robot) (object-handle robot) (joint-index robot joint)))

(defun (setf joint-state) (value robot joint)
  "Set JOINT of ROBOT to VALUE (links and attached objects follow)."
  (set-robot-state-from-joints (list (list joint value)) robot)
  value)

(defun robot-joint-values (robot)
  "Every joint value of ROBOT in joint index order (JOINT-INDEX), mimic joints computed: a
fresh vector of doubles, read in one call (JOINT-STATE reads one joint)."
  (native:robot-joints (whandle robot) (object-handle robot)))

(defun joint-states (robot)
  "Alist (joint-name . position) of every movable joint of ROBOT."
  (let ((v (robot-joint-values robot)))
    (loop for n across (km-joint-names (%model robot))
          for info across (km-joint-info (%model robot))
          for i from 0
          when (member (getf info :type) '(:revolute :continuous :prismatic))
            collect (cons n (aref v i)))))

(defun joint-limits (robot joint)
  "(values lower upper) of JOINT of ROBOT; continuous joints give -pi, pi... as unbounded ±inf
is not meaningful here, they return (values nil nil)."
  (indexed-joint-limits robot (joint-index robot joint)))

(defun indexed-joint-limits-of-info (info)
  "(values lower upper) of a joint of the plist INFO (NIL NIL unless revolute or prismatic)."
  (if (member (getf info :type) '(:revolute :prismatic))
      (values (getf info :lower) (getf info :upper))
      (values nil nil)))

(defun indexed-joint-limits (robot index)
  "JOINT-LIMITS of ROBOT's joint number INDEX."
  (indexed-joint-limits-of-info (aref (km-joint-info (%model robot)) index)))

(defun joint-lower-limit (robot joint) "Lower limit of JOINT." (nth-value 0 (joint-limits robot joint)))
(defun joint-upper-limit (robot joint) "Upper limit of JOINT." (nth-value 1 (joint-limits robot joint)))

(defun clamp-to-joint-limits (robot joint value &optional index)
  "VALUE (a double float) of JOINT of ROBOT (its number INDEX, when known), clamped into the
joint's limits with a warning when it lies beyond them by more than 1e-6 (as CRAM does);
joints without limits keep it."
  (multiple-value-bind (lower upper) (if index
                                         (indexed-joint-limits robot index)
                                         (ignore-errors (joint-limits robot joint)))
    (if (and (realp lower) (realp upper) (< lower upper)
             (or (< value lower) (> value upper)))
        (let ((clamped (to-double (max lower (min upper value)))))
          (when (> (abs (- clamped value)) 1d-6)
            (warn "Joint ~s of ~s: value ~s is beyond its limits [~s, ~s]; set to ~s."
                  joint (name robot) value lower upper clamped))
          clamped)
        value)))

(defun joint-state-pair (entry robot)
  "(name . value) of the joint state ENTRY, (name value) or (name . value)."
  (cond ((and (consp entry) (consp (cdr entry)) (null (cddr entry)))
         (cons (first entry) (second entry)))
        ((and (consp entry) (atom (cdr entry))) entry)
        (t (btr-fail "joint state ~s of ~s, expected (name value)" entry (name robot)))))

(defun check-joint-value (robot name value)
  "VALUE when it is a finite real fit for a joint; else a BTR-ERROR naming ROBOT's joint NAME."
  (unless (and (finite-real-p value) (< (abs value) 1d6))
    (btr-fail "joint ~s of ~s: value ~s, expected a finite real" name (name robot) value))
  value)

(defun clamped-joint-value (robot model index name value)
  "The checked real VALUE of ROBOT's joint number INDEX (called NAME; MODEL its kinematic model)
as a double float, clamped into the joint's limits when it lies beyond them."
  (let ((value (to-double value)))
    (declare (type double-float value) (type fixnum index))
    (if (and (= 1 (sbit (km-limited model) index))
             (or (< value (aref (km-lower model) index)) (> value (aref (km-upper model) index))))
        (clamp-to-joint-limits robot name value index)
        value)))

(defun set-indexed-joint (robot index value)
  "Set ROBOT's joint number INDEX to VALUE (a real), as SET-ROBOT-STATE-FROM-JOINTS sets one
joint (clamped into its limits, links and attached objects moved), for a caller that knows the
joint's index and sets it many times."
  (let* ((model (%model robot))
         (name (svref (km-joint-names model) index))
         (value (clamped-joint-value robot model index name (check-joint-value robot name value)))
         (indices (make-array 1 :element-type '(signed-byte 32) :initial-element index))
         (values (make-array 1 :element-type 'double-float :initial-element value)))
    (native:set-robot-joints (whandle robot) (object-handle robot) indices values)
    robot))

(defun set-robot-state-from-joints (joint-states robot)
  "Set joints of ROBOT from JOINT-STATES: a list of (name value) or (name . value), or a hash
table name → value. All joints are set at once, then links and attached objects move once."
  (let* ((pairs (etypecase joint-states
                  (hash-table (loop for k being the hash-keys of joint-states using (hash-value v)
                                    collect (cons k v)))
                  (list joint-states)))
         (count (length pairs))
         (model (%model robot))
         (indices (make-array count :element-type '(signed-byte 32)))
         (values (make-array count :element-type 'double-float))
         (names (km-joint-names model))
         (next 0))
    (declare (type simple-vector names) (type fixnum next count))
    (loop for entry in pairs for i of-type fixnum from 0
          do (destructuring-bind (n . v) (if (hash-table-p joint-states) entry (joint-state-pair entry robot))
               (unless (stringp n) (btr-fail "joint name ~s of ~s, expected a string" n (name robot)))
               (check-joint-value robot n v)
               ;; the names of a whole state (JOINT-STATES) are the model's own strings, in its
               ;; order: found a few places after the last one without a table
               (let ((index (or (loop for k of-type fixnum from next
                                        below (min (length names) (+ next 8))
                                      when (eq n (svref names k)) return k)
                                (model-joint-index model n)
                                (btr-fail "joint ~s is not a joint of ~s" n (name robot)))))
                 (declare (type fixnum index))
                 (setf next (1+ index))
                 (setf (aref indices i) index
                       (aref values i) (clamped-joint-value robot model index n v)))))
    (native:set-robot-joints (whandle robot) (object-handle robot) indices values)
    robot))

;;; ---- rigid bodies named OBJ.LINK ---------------------------------------------------------------

(defclass rigid-body ()
  ((name :initarg :name :reader name :documentation "Keyword :|OBJNAME.linkname|.")
   (object :initarg :object :reader rigid-body-object)
   (link :initarg :link :reader rigid-body-link :documentation "Link name or NIL for a plain body."))
  (:documentation "One rigid body of an object: a link of an articulated object, or the body of an item."))

(defmethod print-object ((b rigid-body) s)
  (print-unreadable-object (b s :type t) (format s "~s" (name b))))

(defun rigid-body-name (object-name link-name)
  (intern (if link-name
              (format nil "~a.~a" (symbol-name object-name) link-name)
              (symbol-name object-name))
          :keyword))

(defmethod pose ((b rigid-body))
  (let ((o (rigid-body-object b)))
    (if (rigid-body-link b) (link-pose o (rigid-body-link b)) (pose o))))

(defgeneric rigid-bodies (object)
  (:documentation "The rigid bodies of OBJECT, named OBJ.LINK for articulated objects."))

(defmethod rigid-bodies ((o object))
  (list (make-instance 'rigid-body :name (rigid-body-name (name o) nil) :object o :link nil)))

(defmethod rigid-bodies ((r robot-object))
  (mapcar (lambda (l) (make-instance 'rigid-body :name (rigid-body-name (name r) l) :object r :link l))
          (link-names r)))

;;; ---- the :urdf kind ------------------------------------------------------------------------------

(defun build-kinematic-model (world handle urdf)
  (let* ((w (world-handle world))
         (links (coerce (native:robot-link-names w handle) 'simple-vector))
         (joints (coerce (native:robot-joint-names w handle) 'simple-vector))
         (model (make-kinematic-model :urdf urdf :link-names links :joint-names joints
                                      :joint-info (coerce (loop for i below (length joints)
                                                                collect (native:robot-joint-info w handle i))
                                                          'simple-vector))))
    (loop for l across links for i from 0 do (setf (gethash l (km-link-index model)) i))
    ;; the URDF model's own name strings, those its IK chains carry: found by identity
    (when (typep urdf 'cl-urdf:robot)
      (loop for j across joints for i from 0
            for urdf-joint = (gethash j (cl-urdf:joints urdf))
            when urdf-joint do (setf (svref joints i) (cl-urdf:name urdf-joint))))
    (loop for j across joints for i from 0
          do (setf (gethash j (km-joint-index model)) i
                   (gethash j (km-joint-index-eq model)) i))
    (let ((n (length joints)))
      (setf (km-limited model) (make-array n :element-type 'bit :initial-element 0)
            (km-lower model) (make-array n :element-type 'double-float :initial-element 0d0)
            (km-upper model) (make-array n :element-type 'double-float :initial-element 0d0))
      (dotimes (i n)
        (multiple-value-bind (lo hi) (indexed-joint-limits-of-info (svref (km-joint-info model) i))
          (when (and (realp lo) (realp hi) (< lo hi))
            (setf (sbit (km-limited model) i) 1
                  (aref (km-lower model) i) (to-double lo)
                  (aref (km-upper model) i) (to-double hi))))))
    model))

;;; COMPOUND (default NIL, as CRAM's robot objects): true = each collision mesh of a link is one
;;; convex hull per sub-mesh, NIL = one convex hull over all its vertices. A static environment
;;; (collision group :static-filter) gets its meshes as exact triangle meshes either way.
(define-object-kind :urdf (world pose urdf compound collision-group)
  (let* ((model (typecase urdf
                  (cl-urdf:robot urdf)
                  (string (cl-urdf:parse-urdf urdf))
                  (null (btr-fail ":urdf object needs :urdf (a URDF string or a CL-URDF:ROBOT)"))
                  (t (btr-fail ":urdf object: :urdf is ~s, expected a URDF string or a CL-URDF:ROBOT" urdf))))
         (natural-root (loop for l being the hash-values of (cl-urdf:links model)
                             unless (cl-urdf:parent-joint l) return l)))
    ;; a model whose ROOT-LINK was set to another link is re-rooted there
    (unless (eq natural-root (cl-urdf:root-link model))
      (setf model (cl-urdf:parse-urdf (cl-urdf:rerooted-source model))))
    (let* ((moved (cl-urdf:moved-joints model))
           (handle (native:add-urdf (world-handle world) (if moved (car moved) (cl-urdf:source model))
                                    :pose pose :moved-joints (cdr moved)
                                    :exact-meshes (eq collision-group :static-filter)
                                    :single-hull (and (not compound)
                                                      (not (eq collision-group :static-filter))))))
      (values handle 'robot-object nil
              (list :model (build-kinematic-model world handle model))))))

;;; ---- attachments -------------------------------------------------------------------------------

(defun ensure-object (world designator)
  "The object DESIGNATOR (an object, or the name of one in WORLD); an object of WORLD that was
removed from it is an error naming it."
  (cond ((typep designator 'object)
         (when (and (eq (world designator) world)
                    (not (eq (object world (name designator)) designator)))
           (object-gone-error designator "Bullet world query"))
         designator)
        (t (object-or-fail world designator))))

(defun attach-object (parent object &key link loose grasp)
  "Attach OBJECT (an object or name) to PARENT: a robot-object at LINK (a link name), or an item.
Rigid attachments (LOOSE nil) make OBJECT follow the link (or the item); loose ones are only
recorded. As in CRAM, PARENT or OBJECT may be a list: each object is attached to each parent; a
NIL parent warns and attaches nothing (an empty list of objects attaches nothing). Returns
OBJECT (the list of attached objects for a list)."
  (cond ((null parent)
         (warn "ATTACH-OBJECT: no object to attach ~s to (the parent is NIL); nothing attached."
               (if (typep object 'object) (name object) object))
         nil)
        ((consp parent)
         (dolist (p parent object)
           (attach-object p object :link link :loose loose :grasp grasp)))
        ((listp object)
         (mapcar (lambda (o) (attach-object parent o :link link :loose loose :grasp grasp)) object))
        (t (attach-one-object parent object link loose grasp))))

(defun attach-one-object (parent object link loose grasp)
  "ATTACH-OBJECT of one OBJECT to one PARENT."
  (unless (or (typep parent 'object) (and parent (symbolp parent)))
    (btr-fail "ATTACH-OBJECT: parent ~s, expected an object of a Bullet world or an object's name"
              parent))
  (unless (or (typep object 'object) (and object (symbolp object)))
    (btr-fail "ATTACH-OBJECT: object ~s, expected an object of a Bullet world or an object's name"
              object))
  (let* ((world (cond ((typep parent 'object) (world parent))
                      ((typep object 'object) (world object))
                      (t *current-bullet-world*)))
         (parent (ensure-object world parent))
         (object (ensure-object world object))
         (link-i (cond ((typep parent 'robot-object)
                        (unless link (btr-fail "ATTACH-OBJECT: attaching ~s to ~s needs :link" (name object) (name parent)))
                        (link-index parent link))
                       (t -1))))
    (with-live-object (parent 'attach-object)
      (with-live-object (object 'attach-object)
        (native:attach (world-handle world) (object-handle object) (object-handle parent)
                       :link link-i :loose loose)))
    (when (typep parent 'robot-object)
      (setf (%attached parent)
            (append (remove-if (lambda (a) (and (eq (first a) (name object)) (equal (second a) link)))
                               (%attached parent))
                    (list (list (name object) link loose grasp)))))
    object))

(defun detach-object (parent object &key link)
  "Detach OBJECT from PARENT (only from LINK when given)."
  (let* ((world (world parent))
         (object (ensure-object world object)))
    (when (typep parent 'robot-object)
      (setf (%attached parent)
            (remove-if (lambda (a) (and (eq (first a) (name object)) (or (null link) (equal (second a) link))))
                       (%attached parent))))
    (unless (and (typep parent 'robot-object)
                 (find (name object) (%attached parent) :key #'first))
      (with-live-object (parent 'detach-object)
        (with-live-object (object 'detach-object)
          (native:detach (world-handle world) (object-handle object) (object-handle parent))
          (unless (typep parent 'robot-object)
            ;; an attachment between two items holds whichever way it was made
            (native:detach (world-handle world) (object-handle parent) (object-handle object))))))
    object))

(defun detach-all-objects (parent)
  "Detach everything attached to PARENT (a robot, or an item and the items attached to it)."
  (dolist (a (attached-objects parent))
    (detach-object parent (first a))))

(defun attached-objects (object)
  "What is attached to OBJECT. For a robot (an articulated object): a list of (object-name
link-name loose grasp). For an item, as CRAM's object-object attachments: a list of
(other-name loose) for each item attached to it or that it is attached to; LOOSE is true when
that attachment is loose."
  (cond ((typep object 'robot-object) (copy-list (%attached object)))
        ((typep object 'object)
         (let ((world (world object)) (handle (object-handle object)) (entries '()))
           (flet ((name-of (h)
                    (loop for o in (objects world) when (eql (object-handle o) h) return (name o))))
             (loop for (child parent link loose) in (native:attachments (world-handle world))
                   do (let ((other (cond ((and (eql parent handle) (= link -1)) child)
                                         ((eql child handle) parent))))
                        (when other
                          (let ((other-object (find other (objects world) :key #'object-handle)))
                            (when (and other-object (not (typep other-object 'robot-object)))
                              (pushnew (list (name-of other) loose) entries
                                       :key #'first)))))))
           (nreverse entries)))
        (t (btr-fail "ATTACHED-OBJECTS: ~s is not an object of a Bullet world" object))))

(defun object-attached (robot object)
  "The link names of ROBOT that OBJECT (object or name) is attached to."
  (let ((n (if (typep object 'object) (name object) object)))
    (loop for a in (%attached robot) when (eq (first a) n) collect (second a))))

;;; ---- robots and environments of the world -------------------------------------------------------

(defvar *environment-name* nil
  "Name of the environment object (e.g. :IAI-KITCHEN); NIL: the first static articulated object
that is not the robot.")

(defun get-robot-name ()
  "The name of the robot of the current robot description (rob-int facts)."
  (rob-int:current-robot-name))

(defun get-robot-object (&optional (world *current-bullet-world*))
  "The robot's object in WORLD (named as the current robot description), or NIL."
  (let ((n (ignore-errors (get-robot-name))))
    (or (and n (object world n))
        (find-if (lambda (o) (and (typep o 'robot-object)
                                  (equalp (cl-urdf:name (urdf o)) (and n (string n)))))
                 (objects world)))))

(defun get-environment-object (&optional (world *current-bullet-world*))
  "The environment object of WORLD: *ENVIRONMENT-NAME*, or the first articulated object that is
not the robot."
  (if *environment-name*
      (object world *environment-name*)
      (let ((robot (get-robot-object world)))
        (find-if (lambda (o) (and (typep o 'robot-object) (not (eq o robot)))) (objects world)))))

(defun available-arms (robot arms-and-links)
  "The arms of ARMS-AND-LINKS ((arm . link) ...) whose link carries nothing."
  (loop for (arm . link) in arms-and-links
        unless (find link (%attached robot) :key #'second :test #'equal)
          collect arm))

(defun loaded-robot-name ()
  "The described robot (ROB-INT:DESCRIBED-ROBOT-NAMES) loaded in the current world — a robot
object named as it or built from a URDF of its name — else the one ROB-INT:*ROBOT-URDF* is the
model of; NIL when none is."
  (let ((described (rob-int:described-robot-names)))
    (flet ((match (name)
             (and name (find-if (lambda (r) (or (equalp (symbol-name r) (string name))
                                                (eq r (rob-int:urdf-name->robot-name (string name)))))
                                described))))
      (or (loop for o in (objects *current-bullet-world*)
                thereis (and (typep o 'robot-object)
                             (or (and (symbolp (name o)) (find (name o) described))
                                 (match (cl-urdf:name (urdf o))))))
          (and rob-int:*robot-urdf* (match (cl-urdf:name rob-int:*robot-urdf*)))))))

(setf rob-int::*loaded-robot-name-function* 'loaded-robot-name)

(defun loaded-environment-name ()
  "The name of the environment object of the current world, else the keyword of the name of
ROB-INT:*ENVIRONMENT-URDF*; NIL when there is neither."
  (let ((environment (get-environment-object)))
    (cond (environment (name environment))
          (rob-int:*environment-urdf*
           (rob-int:urdf-name->robot-name (cl-urdf:name rob-int:*environment-urdf*))))))

(setf rob-int:*environment-name-function* 'loaded-environment-name)
