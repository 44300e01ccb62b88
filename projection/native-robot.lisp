;;;; cram-native: URDF articulated objects (robots, kitchens).

(in-package :cram-native)

(defcn "cn_robot_add_urdf" :int (w :int) (xml :string) (pose :pointer) (flags :int))
(defcn "cn_robot_add_urdf_moved" :int (w :int) (xml :pointer) (pose :pointer) (flags :int)
  (n :int) (names :pointer) (xyz :pointer) (rpy :pointer))
(defcn "cn_robot_name" :int (w :int) (r :int) (out :pointer))
(defcn "cn_robot_num_links" :int (w :int) (r :int))
(defcn "cn_robot_num_joints" :int (w :int) (r :int))
(defcn "cn_robot_root_link" :int (w :int) (r :int))
(defcn "cn_robot_link_name" :int (w :int) (r :int) (i :int) (out :pointer))
(defcn "cn_robot_joint_name" :int (w :int) (r :int) (i :int) (out :pointer))
(defcn "cn_robot_link_index" :int (w :int) (r :int) (name :string))
(defcn "cn_robot_joint_index" :int (w :int) (r :int) (name :string))
(defcn "cn_robot_joint_info" :int (w :int) (r :int) (j :int) (oi :pointer) (od :pointer))
(defcn "cn_robot_link_parent_joint" :int (w :int) (r :int) (l :int))
(defcn "cn_robot_link_has_body" :int (w :int) (r :int) (l :int))
(defcn "cn_robot_set_joints" :int (w :int) (r :int) (j :pointer) (v :pointer) (n :int))
(defcn "cn_robot_get_joints" :int (w :int) (r :int) (out :pointer) (cap :int))
(defcn "cn_robot_get_joint" :int (w :int) (r :int) (j :int) (out :pointer))
(defcn "cn_robot_link_poses" :int (w :int) (r :int) (out :pointer) (cap :int))
(defcn "cn_robot_link_colors" :int (w :int) (r :int) (out :pointer) (cap :int))
(defcn "cn_robot_link_aabbs" :int (w :int) (r :int) (out :pointer) (cap :int))
(defcn "cn_robot_link_pose" :int (w :int) (r :int) (l :int) (out :pointer))
(defcn "cn_robot_link_poses_if" :int (w :int) (r :int) (j :pointer) (v :pointer) (nj :int)
  (l :pointer) (nl :int) (out :pointer))
(defcn "cn_robot_set_self_collision" :int (w :int) (r :int) (on :int))

(defvar *urdf-foreign-strings* (make-hash-table :test 'eq :weakness :key :synchronized t)
  "URDF text (a Lisp string) → (length . its UTF-8 copy in foreign memory), freed with it: a
belief state built again from the same URDF does not encode the text again.")

;; foreign memory does not survive SAVE-LISP-AND-DIE: a saved core starts without copies
(pushnew 'clear-urdf-foreign-strings sb-ext:*save-hooks*)
(defun clear-urdf-foreign-strings ()
  "Forget the foreign copies of URDF texts (before the image is saved)."
  (clrhash *urdf-foreign-strings*))

(defun urdf-foreign-string (string)
  "The foreign UTF-8 copy of STRING, made once per string object (and again if its length
changed)."
  (let ((entry (gethash string *urdf-foreign-strings*)))
    (if (and entry (= (car entry) (length string)))
        (cdr entry)
        (let ((pointer (cffi:foreign-string-alloc string :encoding :utf-8)))
          (sb-ext:finalize string (lambda () (cffi:foreign-string-free pointer)) :dont-save t)
          (setf (gethash string *urdf-foreign-strings*) (cons (length string) pointer))
          pointer))))

(defun add-urdf (world urdf-string &key (pose '(0 0 0 0 0 0 1)) exact-meshes single-hull
                                        moved-joints)
  "Add the articulated object described by URDF-STRING at base POSE: one kinematic body per
link with collision geometry, every joint at 0.  Collision meshes become one convex hull per
sub-mesh; EXACT-MESHES: exact triangle meshes instead (for static environments); SINGLE-HULL:
one convex hull over all vertices of each mesh.  The two exclude each other.  MOVED-JOINTS, a
list of (joint-name xyz rpy) with the texts of <origin> attributes: the object of the text with
those joints' origins changed, made from the model of URDF-STRING without parsing again.
Returns its handle."
  (when (and exact-meshes single-hull)
    (arg-error 'add-urdf ":exact-meshes ~s and :single-hull ~s exclude each other"
               exact-meshes single-hull))
  (let ((xml (urdf-foreign-string (string-arg urdf-string 'add-urdf "URDF")))
        (flags (cond (exact-meshes 1) (single-hull 2) (t 0))))
    (with-pose-pointer (p pose 'add-urdf)
      (if (null moved-joints)
          (ccall "cn_robot_add_urdf" world xml p flags)
          (let* ((n (length moved-joints))
                 (strings '()))
            (unless (every (lambda (m) (and (listp m) (= 3 (length m)) (every #'stringp m)))
                           moved-joints)
              (arg-error 'add-urdf ":moved-joints ~s, expected a list of (joint-name xyz rpy) strings"
                         moved-joints))
            (cffi:with-foreign-objects ((names :pointer n) (xyz :pointer n) (rpy :pointer n))
              (unwind-protect
                   (progn
                     (loop for (name x r) in moved-joints for i from 0
                           do (loop for (array text) in (list (list names name) (list xyz x) (list rpy r))
                                    do (let ((f (cffi:foreign-string-alloc text :encoding :utf-8)))
                                         (push f strings)
                                         (setf (cffi:mem-aref array :pointer i) f))))
                     (ccall "cn_robot_add_urdf_moved" world xml p flags n names xyz rpy))
                (mapc #'cffi:foreign-string-free strings))))))))

(defun %name-out (fn world robot index)
  (cffi:with-foreign-object (out :pointer)
    (funcall fn world robot index out)
    (cffi:foreign-string-to-lisp (cffi:mem-ref out :pointer))))

(defun robot-name (world robot)
  "Name of ROBOT's URDF model."
  (cffi:with-foreign-object (out :pointer)
    (ccall "cn_robot_name" world robot out)
    (cffi:foreign-string-to-lisp (cffi:mem-ref out :pointer))))

(defun robot-link-count (world robot)
  "Number of links of ROBOT."
  (ccall "cn_robot_num_links" world robot))

(defun robot-joint-count (world robot)
  "Number of joints of ROBOT (fixed ones included)."
  (ccall "cn_robot_num_joints" world robot))

(defun robot-root-link (world robot)
  "Index of ROBOT's root link."
  (ccall "cn_robot_root_link" world robot))

(defun robot-link-name (world robot link)
  "Name of link index LINK of ROBOT."
  (%name-out (lambda (w r i o) (ccall "cn_robot_link_name" w r i o)) world robot link))

(defun robot-joint-name (world robot joint)
  "Name of joint index JOINT of ROBOT."
  (%name-out (lambda (w r i o) (ccall "cn_robot_joint_name" w r i o)) world robot joint))

(defun robot-link-names (world robot)
  "Names of ROBOT's links in index order (root first)."
  (loop for i below (robot-link-count world robot) collect (robot-link-name world robot i)))

(defun robot-joint-names (world robot)
  "Names of ROBOT's joints in index order (parents before children)."
  (loop for i below (robot-joint-count world robot) collect (robot-joint-name world robot i)))

(defun robot-link-index (world robot name)
  "Index of the link called NAME in ROBOT; a NATIVE-ERROR names an unknown link."
  (ccall "cn_robot_link_index" world robot (string-arg name 'robot-link-index "link name")))

(defun robot-joint-index (world robot name)
  "Index of the joint called NAME in ROBOT; a NATIVE-ERROR names an unknown joint."
  (ccall "cn_robot_joint_index" world robot (string-arg name 'robot-joint-index "joint name")))

(defun robot-joint-info (world robot joint)
  "Property list describing JOINT: :type (:fixed :revolute :continuous :prismatic :floating
:planar), :parent and :child link indices, :mimic (joint index or NIL), :lower, :upper,
:velocity, :effort, :axis (x y z), :multiplier, :offset."
  (let ((iv (make-array 4 :element-type '(signed-byte 32)))
        (dv (make-dvec 9)))
    (with-vector-pointers ((p-i iv) (p-d dv)) (ccall "cn_robot_joint_info" world robot joint p-i p-d))
    (list :type (nth (aref iv 0) '(:fixed :revolute :continuous :prismatic :floating :planar))
          :parent (aref iv 1) :child (aref iv 2) :mimic (and (>= (aref iv 3) 0) (aref iv 3))
          :lower (aref dv 0) :upper (aref dv 1) :velocity (aref dv 2) :effort (aref dv 3)
          :axis (list (aref dv 4) (aref dv 5) (aref dv 6))
          :multiplier (aref dv 7) :offset (aref dv 8))))

(defun robot-link-parent-joint (world robot link)
  "Index of the joint whose child is LINK, or NIL for the root."
  (let ((j (ccall "cn_robot_link_parent_joint" world robot link)))
    (and (>= j 0) j)))

(defun robot-link-has-body-p (world robot link)
  "True if LINK has collision geometry (a rigid body)."
  (= 1 (ccall "cn_robot_link_has_body" world robot link)))

(defun set-robot-joints (world robot joints values)
  "Set the joints JOINTS (a sequence of joint indices, an IVEC for speed) to VALUES (a
sequence of reals, a DVEC for speed), then update every link body and attached object once.
Mimic joints follow their leader; fixed joints ignore the value."
  (let ((jv (to-ivec joints 'set-robot-joints "joint indices"))
        (vv (to-dvec values nil 'set-robot-joints "joint values")))
    (declare (type ivec jv) (type dvec vv))
    (unless (= (length jv) (length vv))
      (arg-error 'set-robot-joints "~d joint indices but ~d values" (length jv) (length vv)))
    (with-vector-pointers ((pj jv) (pv vv))
      (ccall "cn_robot_set_joints" world robot pj pv (length jv)))
    t))

(defun robot-joints (world robot &optional out)
  "Every joint value of ROBOT (index order, mimic joints computed) as a DVEC (or into OUT)."
  (let* ((n (ccall "cn_robot_num_joints" world robot))
         (v (or out (make-dvec n))))
    (declare (type dvec v))
    (with-vector-pointers ((p v)) (ccall "cn_robot_get_joints" world robot p (length v)))
    v))

(defun robot-joint (world robot joint)
  "The value of joint number JOINT of ROBOT (mimic joints computed)."
  (let ((v (make-dvec 1)))
    (declare (type dvec v) (dynamic-extent v))
    (with-vector-pointers ((p v)) (ccall "cn_robot_get_joint" world robot joint p))
    (aref v 0)))

(defun robot-link-poses (world robot &optional out)
  "Poses of all links of ROBOT as one DVEC, 7 per link in index order (or into OUT)."
  (let* ((n (ccall "cn_robot_num_links" world robot))
         (v (or out (make-dvec (* 7 n)))))
    (declare (type dvec v))
    (with-vector-pointers ((p v))
      (ccall "cn_robot_link_poses" world robot p (floor (length v) 7)))
    v))

(defun robot-link-colors (world robot)
  "The RGBA colour of every link of the articulated ROBOT (as OBJECT-COLOR gives each), as one
DVEC, 4 per link in index order."
  (let* ((n (ccall "cn_robot_num_links" world robot))
         (v (make-dvec (* 4 n))))
    (declare (type dvec v))
    (with-vector-pointers ((p v)) (ccall "cn_robot_link_colors" world robot p n))
    v))

(defun robot-link-aabbs (world robot &optional out)
  "The axis-aligned bounding box of every link of the articulated ROBOT (as OBJECT-AABB gives
each), as one DVEC (or into OUT), 6 per link in index order: min x y z, max x y z."
  (let* ((n (ccall "cn_robot_num_links" world robot))
         (v (or out (make-dvec (* 6 n)))))
    (declare (type dvec v))
    (unless (>= (length v) (* 6 n))
      (arg-error 'robot-link-aabbs "output of ~d doubles for ~d links" (length v) n))
    (with-vector-pointers ((p v)) (ccall "cn_robot_link_aabbs" world robot p n))
    v))

(defun robot-link-poses-if (world robot joints values links &optional out)
  "The world poses the LINKS (a sequence of link indices, an IVEC for speed) of ROBOT would have
with its JOINTS (indices) at VALUES, the other joints and the base as they are: what
SET-ROBOT-JOINTS then ROBOT-LINK-POSE would give, the world left unchanged. One DVEC (or OUT),
7 per link in the order of LINKS."
  (let* ((jv (to-ivec joints 'robot-link-poses-if "joint indices"))
         (vv (to-dvec values nil 'robot-link-poses-if "joint values"))
         (lv (to-ivec links 'robot-link-poses-if "link indices"))
         (v (or out (make-dvec (* 7 (length lv))))))
    (declare (type ivec jv lv) (type dvec vv v))
    (unless (= (length jv) (length vv))
      (arg-error 'robot-link-poses-if "~d joint indices but ~d values" (length jv) (length vv)))
    (unless (>= (length v) (* 7 (length lv)))
      (arg-error 'robot-link-poses-if "output of ~d doubles for ~d links" (length v) (length lv)))
    (with-vector-pointers ((pj jv) (pv vv) (pl lv) (po v))
      (ccall "cn_robot_link_poses_if" world robot pj pv (length jv) pl (length lv) po))
    v))

(defun robot-link-pose (world robot link &optional out)
  "World pose of LINK (an index) of ROBOT as a DVEC of 7 (or into OUT)."
  (let ((v (or out (make-dvec 7))))
    (declare (type dvec v))
    (with-vector-pointers ((p v)) (ccall "cn_robot_link_pose" world robot link p))
    v))

(defun set-robot-self-collision (world robot enabled)
  "Whether ROBOT's links are checked against each other (default: no)."
  (ccall "cn_robot_set_self_collision" world robot (if enabled 1 0))
  enabled)
