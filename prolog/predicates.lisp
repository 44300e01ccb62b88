;;;; Predicates: one PRED per functor symbol, holding its clause sources, handler or native code
;;;; and the compiled entry function (M ARGS CONT) that every call goes through.

(in-package :cram-prolog)

(declaim (optimize (speed 3) (safety 1) (debug 0)))

(define-condition prolog-error (error)
  ((message :initarg :message :reader prolog-error-message))
  (:report (lambda (c s) (write-string (prolog-error-message c) s)))
  (:documentation "An error in a Prolog program or query: a malformed goal or clause, a
predicate called with an unbound goal, and similar."))

(define-condition prolog-resource-error (prolog-error) ()
  (:documentation "A query ran out of stack or heap (an endless recursion, a term nested too
deeply): it used more heap than *PROLOG-HEAP-LIMIT* allows, or overflowed the Lisp stack. The
query is abandoned; the image stays usable."))

(defun prolog-error (format &rest args)
  "Signal PROLOG-ERROR with the formatted message (terms printed at most 8 levels deep and 30
elements long)."
  (error 'prolog-error :message (let ((*print-level* 8) (*print-length* 30) (*print-circle* nil))
                                  (apply #'format nil format args))))

(defvar *break-on-lisp-errors* nil
  "When NIL, a Lisp error inside LISP-FUN, LISP-PRED (and the other predicates calling Lisp
functions) prints a warning and the goal fails. When true, the error is signalled. Errors of
the functions registered with PROPAGATE-LISP-ERRORS (those behind predicates that change
something: assert, retract, simulate) are always signalled.")

(defvar *database-lock* (sb-thread:make-mutex :name "cram-prolog database")
  "Protects the predicate table, the fact groups and the compilation of predicates.")

(defmacro with-database-lock (() &body body)
  `(sb-thread:with-recursive-lock (*database-lock*) ,@body))

(defstruct (pred (:constructor %make-pred (functor)) (:copier nil))
  "Everything known about the predicate named FUNCTOR."
  (functor nil :type symbol)
  (entry #'identity :type function)     ; (lambda (m args cont)) → true on a solution
  ;; (lambda (m a1 ... an cont)): the same for a call with N = 1 .. 4 arguments passed one by
  ;; one, so that a call need not cons its argument list
  (entry1 #'identity :type function)
  (entry2 #'identity :type function)
  (entry3 #'identity :type function)
  (entry4 #'identity :type function)
  (sources '())                         ; ((group-name . clauses) ...) in registration order
  (dynamic '())                         ; facts added with ADD-FACT, in order
  (handler nil)                         ; (lambda (bindings &rest args)) → lazy list of alists
  (native nil)                          ; (lambda (m args cont)) for built-ins
  (native-positional nil)               ; NIL or (n . (lambda (m a1 ... an cont))) for built-ins
  (control nil)                         ; compiler of a control construct: (lambda (args)) → goal
  (warned nil))

(defvar *predicates* (make-hash-table :test 'eq :synchronized t)
  "Functor symbol → PRED.")

(defun make-lazy-entry (pred)
  "An entry that installs PRED's real entry on first call, then calls it."
  (lambda (m args cont)
    (install-entry pred)
    (funcall (pred-entry pred) m args cont)))

(defun make-lazy-positional-entry (pred)
  "An entry (M A1 ... AN CONT), N from 1 to 4, that installs PRED's real entries on first
call, then calls the one for N arguments."
  (lambda (m &rest args-and-cont)
    (install-entry pred)
    (apply (the function (positional-entry pred (1- (length args-and-cont)))) m args-and-cont)))

(defun positional-entry (pred n)
  "PRED's entry for calls with N arguments passed one by one."
  (ecase n
    (1 (pred-entry1 pred)) (2 (pred-entry2 pred)) (3 (pred-entry3 pred)) (4 (pred-entry4 pred))))

(defun set-positional-entries (pred function)
  "Make (FUNCTION n) PRED's entry for calls with N arguments passed one by one, N from 1 to 4."
  (declare (type function function))
  (setf (pred-entry1 pred) (funcall function 1)
        (pred-entry2 pred) (funcall function 2)
        (pred-entry3 pred) (funcall function 3)
        (pred-entry4 pred) (funcall function 4)))

(defun set-lazy-entries (pred)
  (setf (pred-entry pred) (make-lazy-entry pred))
  (let ((lazy (make-lazy-positional-entry pred)))
    (set-positional-entries pred (lambda (n) (declare (ignore n)) lazy))))

(defmacro listing-entry (n entry)
  "An entry (M A1 ... AN CONT) calling the entry function ENTRY (a form evaluated at each call)
with the argument list."
  (let ((as (loop for i from 1 to n collect (gensym "A"))))
    `(lambda (m ,@as cont) (funcall (the function ,entry) m (list ,@as) cont))))

(defun listing-entries (pred)
  "Entries for 1 to 4 arguments passed one by one that call PRED's current entry with the list."
  (lambda (n)
    (ecase n
      (1 (listing-entry 1 (pred-entry pred))) (2 (listing-entry 2 (pred-entry pred)))
      (3 (listing-entry 3 (pred-entry pred))) (4 (listing-entry 4 (pred-entry pred))))))

(defun ensure-pred (functor)
  "The PRED of FUNCTOR, created when new."
  (or (gethash functor *predicates*)
      (with-database-lock ()
        (or (gethash functor *predicates*)
            (let ((pred (%make-pred functor)))
              (set-lazy-entries pred)
              (setf (gethash functor *predicates*) pred))))))

(defun pred-defined-p (pred)
  (or (pred-native pred) (pred-control pred) (pred-handler pred)
      (pred-sources pred) (pred-dynamic pred)))

(defvar *builtin-names* (make-hash-table :test 'equal)
  "Symbol name → built-in PRED, for goals written with a same-named symbol of another package.")

(defun resolve-functor (functor)
  "The PRED a goal with FUNCTOR calls: FUNCTOR's own when it has a definition, otherwise a
built-in of the same name, otherwise FUNCTOR's (undefined) one."
  (unless (and functor (symbolp functor))
    (prolog-error "A goal's functor must be a non-nil symbol, got ~s." functor))
  (let ((pred (ensure-pred functor)))
    (if (pred-defined-p pred)
        pred
        (or (gethash (symbol-name functor) *builtin-names*) pred))))

(declaim (type (cons fixnum null) *generation*))
(defvar *generation* (list 0)
  "A cell holding the number of changes made to the database so far.")

(defun database-generation ()
  "A number that changes whenever a clause, fact or handler of any predicate changes: what a
query over facts returned stays valid while it is the same."
  (car *generation*))

(defun invalidate-pred (pred)
  "Make PRED recompile on its next call (and count a change of the database)."
  (sb-ext:atomic-incf (car *generation*))
  (set-lazy-entries pred))

(defun undefined-entry (pred)
  (lambda (m args cont)
    (declare (ignore m args cont))
    (unless (pred-warned pred)
      (setf (pred-warned pred) t)
      (warn "Trying to prove a goal with the undefined functor ~s: it fails."
            (pred-functor pred)))
    nil))

(defun install-entry (pred)
  "Compute and store PRED's entries from its current definition."
  (with-database-lock ()
    (cond ((or (pred-native pred) (pred-control pred))
           (setf (pred-entry pred) (or (pred-native pred) (control-entry pred)))
           (let ((positional (and (pred-native pred) (pred-native-positional pred))))
             (set-positional-entries
              pred (lambda (n)
                     (if (and positional (= n (the fixnum (car positional))))
                         (cdr positional)
                         (funcall (the function (listing-entries pred)) n))))))
          (t
           (let* ((clauses (loop for (nil . forms) in (pred-sources pred)
                                 append (mapcar #'compile-clause forms)))
                  (clauses (append clauses (mapcar #'compile-clause (pred-dynamic pred))))
                  (clause-entry (if clauses
                                    (make-clauses-entry clauses)
                                    (undefined-entry pred))))
             (setf (pred-entry pred)
                   (if (pred-handler pred)
                       (make-handler-entry pred (pred-handler pred) (and clauses clause-entry))
                       clause-entry))
             (set-positional-entries
              pred (lambda (n)
                     (or (and clauses (not (pred-handler pred))
                              (make-positional-clauses-entry clauses n))
                         (funcall (the function (listing-entries pred)) n)))))))))

(defun control-entry (pred)
  "Entry of a control construct called through CALL or a query: compile the goal and run it."
  (lambda (m args cont)
    (meta-call m (cons (pred-functor pred) args) cont)))
