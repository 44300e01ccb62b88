;;;; The belief state as TF frames: map → robot root (the robot object's pose), every robot link
;;;; relative to its parent link, the environment's links under a prefix, map → each item.

(in-package :roslisp-utilities)

(defvar *tf-fixed-frame* "map"
  "The frame the belief state's roots (robot, environment, items) are published in.")

(defvar *environment-tf-prefix* :object-name
  "TF prefix of the environment's links: a string (\"iai_kitchen\" gives iai_kitchen/sink_area),
NIL or \"\" for none, or :OBJECT-NAME for the environment object's name with underscores
(:IAI-KITCHEN → iai_kitchen). Other articulated objects that are neither the robot nor the
environment always get their object name as prefix; the robot's links have none.")

(defun object-frame-name (object)
  "The TF frame of an item OBJECT (an object or its name): its name with underscores,
BOTTLE-1 → \"bottle_1\"."
  (rosify-underscores-lisp-name (if (typep object 'btr:object) (btr:name object) object)))

(defun prefixed (prefix frame)
  (if (and prefix (plusp (length prefix))) (concatenate 'string prefix "/" frame) frame))

(defun check-prefix (prefix)
  (unless (or (null prefix) (eq prefix :object-name) (stringp prefix))
    (ros-fail "*ENVIRONMENT-TF-PREFIX* is ~s, expected a string, NIL or :OBJECT-NAME" prefix))
  prefix)

(defun check-frame-name (frame what)
  (unless (and (stringp frame) (plusp (length frame)))
    (ros-fail "~a is ~s, expected a non-empty frame name string" what frame))
  frame)

(defvar *link-tree-cache* (make-hash-table :test 'eq :weakness :key)
  "CL-URDF:ROBOT → list of (link-name . parent-link-name), parents before children.")

(defun urdf-link-tree (urdf)
  "The links of URDF below its root as (link-name . parent-link-name), parents first."
  (or (gethash urdf *link-tree-cache*)
      (setf (gethash urdf *link-tree-cache*)
            (let ((edges '()) (queue (list (cl-urdf:root-link urdf))))
              (loop while queue
                    do (let ((link (pop queue)))
                         (dolist (joint (sort (copy-list (cl-urdf:child-joints link)) #'string<
                                              :key #'cl-urdf:name))
                           (let ((child (cl-urdf:child joint)))
                             (push (cons (cl-urdf:name child) (cl-urdf:name link)) edges)
                             (setf queue (append queue (list child)))))))
              (nreverse edges)))))

(defun articulated-roles (world)
  "Alist (robot-object . tf-prefix) for every articulated object of WORLD: the robot (the current
robot's object, else the first articulated object that is not the environment) without prefix,
the environment with *ENVIRONMENT-TF-PREFIX*, the others prefixed with their names."
  (let* ((env (btr:get-environment-object world))
         (articulated (remove-if-not #'btr:robot-object-p (btr:objects world)))
         (robot (or (btr:get-robot-object world)
                    (find-if (lambda (o) (not (eq o env))) articulated))))
    (loop for o in articulated
          collect (cons o (cond ((eq o robot) nil)
                                ((eq o env)
                                 (let ((p (check-prefix *environment-tf-prefix*)))
                                   (if (eq p :object-name) (rosify-underscores-lisp-name (btr:name o)) p)))
                                (t (rosify-underscores-lisp-name (btr:name o))))))))

(defun relative-transform (parent-pose child-pose)
  "The transform of CHILD-POSE's frame in PARENT-POSE's frame."
  (cl-transforms:transform* (cl-transforms:transform-inv (cl-transforms:pose->transform parent-pose))
                            (cl-transforms:pose->transform child-pose)))

(defun articulated-transforms (object prefix fixed-frame)
  "TF edges of the articulated OBJECT: FIXED-FRAME → root from the object's pose, then each link
in its parent link's frame, every frame name with PREFIX."
  (let* ((urdf (btr:urdf object))
         (root (cl-urdf:name (cl-urdf:root-link urdf)))
         (poses (make-hash-table :test 'equal))
         (edges (list (list fixed-frame (prefixed prefix root)
                            (cl-transforms:pose->transform (btr:pose object))))))
    (flet ((link-pose (name)
             (or (gethash name poses)
                 (setf (gethash name poses) (btr:link-pose object name)))))
      (loop for (link . parent) in (urdf-link-tree urdf)
            when (and (btr:link-exists-p object link) (btr:link-exists-p object parent))
              do (push (list (prefixed prefix parent) (prefixed prefix link)
                             (relative-transform (link-pose parent) (link-pose link)))
                       edges)))
    (nreverse edges)))

(defun call-with-world-lock (world thunk)
  "Call THUNK holding WORLD's lock, so objects are not added or removed meanwhile."
  (let ((lock (btr:world-lock world)))
    (if lock
        (bt:with-recursive-lock-held (lock) (funcall thunk))
        (funcall thunk))))

(defun check-world (world)
  (unless (typep world 'btr:bt-reasoning-world)
    (ros-fail "~s is not a belief state, expected a BTR:BT-REASONING-WORLD (e.g. BTR:*CURRENT-BULLET-WORLD*)"
              world))
  world)

(defun belief-state-transforms (&key (world btr:*current-bullet-world*) (fixed-frame *tf-fixed-frame*))
  "The TF edges of WORLD as a list of (parent-frame child-frame cl-transforms:transform):
FIXED-FRAME → robot root from the robot object's pose and every robot link relative to its
parent link; the same for the environment (frames prefixed as *ENVIRONMENT-TF-PREFIX* says)
and other articulated objects (prefixed with their names); FIXED-FRAME → each item (frame
OBJECT-FRAME-NAME) at its pose."
  (check-world world)
  (check-frame-name fixed-frame "the fixed frame")
  (call-with-world-lock
   world
   (lambda ()
     (append
      (loop for (object . prefix) in (articulated-roles world)
            append (articulated-transforms object prefix fixed-frame))
      (loop for o in (btr:objects world)
            when (typep o 'btr:item)
              collect (list fixed-frame (object-frame-name o)
                            (cl-transforms:pose->transform (btr:pose o))))))))
