;;;; Worlds: a BT-WORLD owns one native physics world; a BT-REASONING-WORLD adds the named
;;;; objects. Copies share collision shapes and keep every object handle.

(in-package :cram-bullet-reasoning)

(define-condition btr-error (error)
  ((message :initarg :message :reader btr-error-message))
  (:report (lambda (c s) (write-string (btr-error-message c) s)))
  (:documentation "Bad input to the belief state: unknown object, link or joint, bad pose or key."))

(defun btr-fail (fmt &rest args)
  "Signal a BTR-ERROR with the formatted message."
  (error 'btr-error :message (apply #'format nil fmt args)))

(defclass bt-world ()
  ((handle :initarg :handle :reader world-handle
           :documentation "Handle of the native world.")
   (lock :initform (bt:make-recursive-lock "bullet world") :reader world-lock))
  (:documentation "A physics world in the native shim (Bullet, double precision)."))

(defclass bt-reasoning-world (bt-world)
  ((objects :initform (make-hash-table :test 'eq) :reader %objects
            :documentation "Object name → OBJECT.")
   (order :initform '() :accessor %object-order
          :documentation "Object names, oldest first (for deterministic iteration).")
   (by-handle :initform (make-hash-table) :reader %objects-by-handle
              :documentation "Native object handle → OBJECT."))
  (:documentation "A physics world whose objects have names: the belief state of CRAM."))

(defmethod initialize-instance :after ((world bt-world) &key handle)
  (let ((h (or handle (native:make-world))))
    (setf (slot-value world 'handle) h)
    (tg:finalize world (lambda () (ignore-errors (native:destroy-world h))))))

(defmethod print-object ((world bt-reasoning-world) stream)
  (print-unreadable-object (world stream :type t :identity t)
    (format stream "~d objects" (length (%object-order world)))))

(defvar *current-bullet-world* (make-instance 'bt-reasoning-world)
  "The belief state that plans, Prolog predicates and the projection use.")

(defun destroy-world (world)
  "Release the native world of WORLD now (it is unusable afterwards)."
  (let ((h (world-handle world)))
    (tg:cancel-finalization world)
    (when (native:world-alive-p h) (native:destroy-world h))
    t))

(defmacro with-world-lock ((world) &body body)
  `(bt:with-recursive-lock-held ((world-lock ,world)) ,@body))

(defun objects (&optional (world *current-bullet-world*))
  "Every object of WORLD, oldest first."
  (mapcar (lambda (n) (gethash n (%objects world))) (%object-order world)))

(defun object-names (&optional (world *current-bullet-world*))
  "The names of the objects of WORLD, oldest first."
  (copy-list (%object-order world)))

(defvar *object-name-resolvers* '()
  "Functions (world name) returning the name of an existing object that NAME stands for, or NIL:
the aliases of older code's names (e.g. CRAM-PR2-DESCRIPTION:PR2 for :PR2), consulted by OBJECT
only when no object is called NAME.")

(defun object (world name)
  "The object called NAME in WORLD, or NIL (see *OBJECT-NAME-RESOLVERS* for aliases)."
  (or (values (gethash name (%objects world)))
      (loop for resolver in *object-name-resolvers*
            for alias = (funcall resolver world name)
            when (and alias (not (eq alias name)) (gethash alias (%objects world)))
              return (values (gethash alias (%objects world))))))

(defun object-by-handle (world handle)
  "The object of WORLD with the native HANDLE, or NIL."
  (values (gethash handle (%objects-by-handle world))))

(defun %register-object (world object)
  (with-world-lock (world)
    (setf (gethash (name object) (%objects world)) object)
    (setf (gethash (object-handle object) (%objects-by-handle world)) object)
    (setf (%object-order world) (append (%object-order world) (list (name object))))
    object))

(defun %unregister-object (world name)
  (with-world-lock (world)
    (let ((o (gethash name (%objects world))))
      (when o (remhash (object-handle o) (%objects-by-handle world))))
    (remhash name (%objects world))
    (setf (%object-order world) (remove name (%object-order world)))))

(defgeneric copy-object (object world)
  (:documentation "A copy of OBJECT belonging to WORLD (a copy of OBJECT's world)."))

(defun copy-world (&optional (world *current-bullet-world*))
  "A new world with copies of every object of WORLD at their current poses and joint states.
Collision shapes are shared, so copying is cheap."
  (check-world world 'copy-world)
  (with-world-lock (world)
    (let ((new (make-instance (class-of world) :handle (native:copy-world (world-handle world)))))
      (dolist (o (objects world))
        (%register-object new (copy-object o new)))
      new)))

(defmacro with-copied-world ((&optional (world '*current-bullet-world*)) &body body)
  "Run BODY with *CURRENT-BULLET-WORLD* bound to a copy of WORLD; the copy is destroyed after."
  (let ((copy (gensym "COPY")))
    `(let* ((,copy (copy-world ,world))
            (*current-bullet-world* ,copy))
       (unwind-protect (progn ,@body)
         (destroy-world ,copy)))))

(defmacro with-world ((world) &body body)
  "Run BODY with *CURRENT-BULLET-WORLD* bound to WORLD."
  `(let ((*current-bullet-world* ,world)) ,@body))

(defun finite-real-p (x)
  "True for a real that is neither NaN nor an infinity."
  (and (realp x)
       (not (and (floatp x) (or (sb-ext:float-nan-p x) (sb-ext:float-infinity-p x))))))

(defparameter *max-simulation-steps* 100000000
  "The most physics steps one call of SIMULATE may take.")

(defun check-world (world where)
  "Signal a BTR-ERROR naming WHERE unless WORLD is a Bullet world that has not been destroyed."
  (unless (typep world 'bt-world)
    (btr-fail "~a: expected a Bullet world (e.g. BTR:*CURRENT-BULLET-WORLD*), got ~s" where world))
  (unless (native:world-alive-p (world-handle world))
    (btr-fail "~a: the world ~a has been destroyed (DESTROY-WORLD) and cannot be used" where
              (world-description world)))
  world)

(defun world-description (world)
  "A short text naming WORLD for messages: its class, objects and identity."
  (let ((*print-length* 6))
    (if (typep world 'bt-reasoning-world)
        (format nil "~a with objects ~s" (princ-to-string world) (%object-order world))
        (princ-to-string world))))

(defun simulate (world seconds &optional (dt 0.01d0))
  "Advance WORLD's physics by SECONDS in steps of DT (ceiling of SECONDS/DT steps; once nothing
moves any more, the remaining steps are skipped, see CRAM-NATIVE:SIMULATE)."
  (check-world world 'simulate)
  (unless (and (finite-real-p seconds) (>= seconds 0))
    (btr-fail "SIMULATE: seconds is ~s, expected a finite non-negative real" seconds))
  (unless (and (finite-real-p dt) (> dt 0))
    (btr-fail "SIMULATE: dt is ~s, expected a finite positive real" dt))
  (when (> (/ (rational seconds) (rational dt)) *max-simulation-steps*)
    (btr-fail "SIMULATE: ~s seconds in steps of ~s need more than ~:d steps (BTR::*MAX-SIMULATION-STEPS*)"
              seconds dt *max-simulation-steps*))
  (with-world-lock (world)
    (native:simulate (world-handle world) (coerce seconds 'double-float) (coerce dt 'double-float))
    world))

(defun step-world (world &optional (dt 0.01d0))
  "Advance WORLD's physics by one step of DT seconds (the Prolog predicate STEP, which is
CL:STEP as in CRAM, so that BTR can be used next to COMMON-LISP)."
  (simulate world dt dt))
