;;;; Projection environments: a named set of special variable bindings, process modules and
;;;; startup / shutdown code under which plans run against a simulated robot.

(in-package :cram-projection)

(defvar *projection-environment* nil
  "The name of the projection environment the current code runs in, NIL outside any.")

(pushnew '*projection-environment* cpl:*inherited-specials*)
(pushnew 'desig:*default-role* cpl:*inherited-specials*)

(defvar *projection-environments* (make-hash-table :test 'eq)
  "Name -> (runner . process-module-names) of every defined projection environment.")

(defun projection-environment-names ()
  "The names of all defined projection environments, sorted."
  (sort (loop for name being the hash-keys of *projection-environments* collect name)
        #'string< :key #'symbol-name))

(defun find-projection-environment (name)
  (or (gethash name *projection-environments*)
      (error "Unknown projection environment ~s: expected one of ~:[none defined~;~:*~{~s~^, ~}~]."
             name (projection-environment-names))))

(defun projection-environment-process-modules (name)
  "The names of the process modules the projection environment NAME runs."
  (cdr (find-projection-environment name)))

(defmacro define-projection-environment (name &key special-variable-initializers
                                                   process-module-definitions
                                                   startup shutdown)
  "Define (or redefine) the projection environment NAME.
SPECIAL-VARIABLE-INITIALIZERS: ((variable init-form)...); each WITH-PROJECTION-ENVIRONMENT
binds the variables (as specials, inherited by plan tasks) to freshly evaluated init forms,
in order. PROCESS-MODULE-DEFINITIONS: the names of the process modules that run inside.
STARTUP and SHUTDOWN: forms run after binding and when leaving (even by a non-local exit)."
  (check-type name (and symbol (not null)))
  (dolist (entry special-variable-initializers)
    (unless (and (consp entry) (symbolp (first entry)) (first entry)
                 (or (null (cdr entry)) (null (cddr entry))))
      (error "DEFINE-PROJECTION-ENVIRONMENT ~s: special variable initializer ~s: expected ~
              (variable init-form)." name entry)))
  (dolist (module process-module-definitions)
    (unless (and (symbolp module) module)
      (error "DEFINE-PROJECTION-ENVIRONMENT ~s: expected process module names, got ~s."
             name module)))
  (let ((variables (mapcar #'first special-variable-initializers))
        (thunk (gensym "THUNK")))
    `(progn
       ,@(mapcar (lambda (v) `(pushnew ',v cpl:*inherited-specials*)) variables)
       (setf (gethash ',name *projection-environments*)
             (cons (lambda (,thunk)
                     (let* (,@special-variable-initializers)
                       (declare (special ,@variables))
                       (cpm::call-with-process-modules-running
                        ',process-module-definitions
                        (lambda ()
                          (unwind-protect
                               (progn ,startup (funcall ,thunk))
                            ,shutdown)))))
                   ',process-module-definitions))
       ',name)))

(defun call-with-projection-environment (name thunk)
  (let ((runner (car (find-projection-environment name)))
        (*projection-environment* name)
        ;; motions are instants here: concurrent children start in order (same seed, same run)
        (cpl:*ordered-concurrency* t))
    (call-with-special-projection-variables (lambda () (funcall runner thunk)))))

(defmacro with-projection-environment (name &body body)
  "Run BODY inside the projection environment NAME (an unquoted symbol; any other form is
evaluated to get the name): its specials are bound, its process modules run,
its startup and shutdown forms run around BODY, and CPL:*ORDERED-CONCURRENCY* is true (the
children of PAR and PURSUE start in order). Returns the values of BODY."
  `(call-with-projection-environment ,(if (symbolp name) `',name name)
                                     (lambda () ,@body)))
