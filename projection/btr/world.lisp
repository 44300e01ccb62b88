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

(defun object (world name)
  "The object called NAME in WORLD, or NIL."
  (values (gethash name (%objects world))))

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

(defun simulate (world seconds &optional (dt 0.01d0))
  "Advance WORLD's physics by SECONDS in steps of DT (ceiling of SECONDS/DT steps)."
  (unless (and (realp seconds) (>= seconds 0))
    (btr-fail "SIMULATE: seconds is ~s, expected a non-negative real" seconds))
  (unless (and (realp dt) (> dt 0))
    (btr-fail "SIMULATE: dt is ~s, expected a positive real" dt))
  (with-world-lock (world)
    (native:simulate (world-handle world) (coerce seconds 'double-float) (coerce dt 'double-float))
    world))

(defun step (world &optional (dt 0.01d0))
  "Advance WORLD's physics by one step of DT seconds."
  (simulate world dt dt))
