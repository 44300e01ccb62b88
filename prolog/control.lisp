;;;; Control constructs, compiled inline into clause bodies: and, or, not, ->, *->, once, call,
;;;; cut, true, fail, findall, bagof, setof, forall, every. Called through CALL or as a query,
;;;; the goal is compiled on the spot.
;;;;
;;;; Cut: a cut inside AND, OR and the branches of -> / *-> cuts the clause (or the query);
;;;; NOT, ONCE, CALL, FINDALL, BAGOF, SETOF, FORALL, EVERY and the condition of -> / *-> are
;;;; opaque to it (a cut there only commits inside them), as in ISO Prolog.

(in-package :cram-prolog)

(declaim (optimize (speed 3) (safety 1) (debug 0)))

(defun register-control (name compiler)
  (with-database-lock ()
    (let ((pred (ensure-pred name)))
      (setf (pred-control pred) compiler)
      (setf (gethash (symbol-name name) *builtin-names*) pred)
      (invalidate-pred pred)
      name)))

(eval-when (:compile-toplevel :load-toplevel :execute)
(defun lambda-list-arity (lambda-list)
  "Minimum and maximum (NIL: any) number of arguments of the simple LAMBDA-LIST."
  (let ((required (or (position-if (lambda (x) (member x lambda-list-keywords)) lambda-list)
                      (length lambda-list)))
        (optional (let ((o (member '&optional lambda-list)))
                    (if o (or (position-if (lambda (x) (member x lambda-list-keywords)) (cdr o))
                              (length (cdr o)))
                        0))))
    (values required (if (member '&rest lambda-list) nil (+ required optional))))))

(defun check-goal-arity (name args min max)
  (let ((n (length args)))
    (unless (and (>= n min) (or (null max) (<= n max)))
      (prolog-error "The goal ~s has ~d argument~:p, but ~s takes ~a."
                    (cons name args) n name
                    (cond ((null max) (format nil "at least ~d" min))
                          ((= min max) min)
                          (t (format nil "~d to ~d" min max)))))))

(defmacro define-control (name lambda-list &body body)
  "Define the control construct NAME: BODY compiles the goal's arguments (destructured with
LAMBDA-LIST) into a goal function (M FRAME CONT BARRIER)."
  (let ((args (gensym "ARGS")))
    (multiple-value-bind (min max) (lambda-list-arity lambda-list)
      `(register-control
        ',name
        (lambda (,args)
          (unless (alexandria:proper-list-p ,args)
            (prolog-error "The goal ~s: ~s needs a proper list of arguments, got ~s."
                          (cons ',name ,args) ',name ,args))
          (check-goal-arity ',name ,args ,min ,max)
          (destructuring-bind ,lambda-list ,args ,@body))))))

(defun resume-continue (m index)
  "Choice point: pop it and call the continuation in data slot 0."
  (let ((cont (cp-data m index 0)))
    (setf (machine-cp-top m) index)
    (funcall (the function cont))))

(defun resume-fail (m index)
  (setf (machine-cp-top m) index)
  nil)

(define-control and (&rest goals) (compile-body goals))

(define-control true () (lambda (m frame cont barrier)
                          (declare (ignore m frame barrier))
                          (funcall (the function cont))))

(define-control fail () (lambda (m frame cont barrier)
                          (declare (ignore m frame cont barrier))
                          nil))

(define-control cut () (lambda (m frame cont barrier)
                         (declare (ignore frame))
                         (cut-to m barrier)
                         (funcall (the function cont))))

(defun compile-or (goals)
  (cond ((null goals) (compile-goal '(fail)))
        ((null (cdr goals)) (compile-goal (car goals)))
        (t (let* ((first (compile-goal (car goals)))
                  (rest (compile-or (cdr goals)))
                  (resume (lambda (m index)
                            (let ((frame (cp-data m index 0))
                                  (cont (cp-data m index 1))
                                  (barrier (cp-data m index 2)))
                              (setf (machine-cp-top m) index)
                              (funcall (the function rest) m frame cont barrier)))))
             (declare (type function first rest))
             (lambda (m frame cont barrier)
               (push-cp m resume frame cont barrier)
               (funcall first m frame cont barrier))))))

(define-control or (&rest goals) (compile-or goals))

(define-control not (goal &rest more-goals)
  (let ((g (compile-body (cons goal more-goals))))
    (declare (type function g))
    (lambda (m frame cont barrier)
      (declare (ignore barrier))
      (let ((h (machine-cp-top m)))
        (push-cp m #'resume-continue cont nil nil)
        (funcall g m frame (lambda () (cut-to m h)) (machine-cp-top m))))))

(define-control once (&rest goals)
  (let ((g (compile-body goals)))
    (declare (type function g))
    (lambda (m frame cont barrier)
      (declare (ignore barrier))
      (let ((h (machine-cp-top m)))
        (funcall g m frame (lambda () (cut-to m h) (funcall (the function cont))) h)))))

(defun compile-if-then-else (condition then else soft)
  (let ((c (compile-goal condition))
        (then (compile-goal then))
        (else (and else (compile-goal else))))
    (declare (type function c then))
    (let ((resume (and else
                       (lambda (m index)
                         (let ((frame (cp-data m index 0))
                               (cont (cp-data m index 1))
                               (barrier (cp-data m index 2)))
                           (setf (machine-cp-top m) index)
                           (funcall (the function else) m frame cont barrier))))))
      (if soft
          (lambda (m frame cont barrier)
            (let ((e (and resume (push-cp m resume frame cont barrier))))
              (funcall c m frame
                       (lambda ()
                         (when e (setf (svref (machine-cps m) (1+ (the fixnum e))) #'resume-fail))
                         (funcall then m frame cont barrier))
                       (machine-cp-top m))))
          (lambda (m frame cont barrier)
            (let ((h (machine-cp-top m)))
              (when resume (push-cp m resume frame cont barrier))
              (funcall c m frame
                       (lambda () (cut-to m h) (funcall then m frame cont barrier))
                       (machine-cp-top m))))))))

(define-control -> (condition then &optional else)
  (compile-if-then-else condition then else nil))

(define-control *-> (condition then &optional else)
  (compile-if-then-else condition then else t))

(define-control call (goal &rest extra-args)
  (let ((goal-source goal)
        (build (compile-build (cons goal extra-args))))
    (declare (type function build))
    (lambda (m frame cont barrier)
      (declare (ignore barrier))
      (let* ((parts (funcall build frame))
             (goal (deref (car parts))))
        (meta-call m (if (cdr parts)
                         (append (if (consp goal) goal (list goal)) (cdr parts))
                         goal)
                   cont (cons 'call (cons goal-source extra-args)))))))

(defun meta-call (m goal cont &optional source)
  "Prove the run-time term GOAL, then call CONT. Opaque to cut. SOURCE, the goal as written,
names it in errors."
  (let ((goal (deref goal)))
    (when (pvar-p goal)
      (prolog-error "~@[~s: ~]CALL of an unbound variable: a goal was expected." source))
    (unless (consp goal)
      (prolog-error "A goal must be a list (functor arg...), got ~s." goal))
    (let* ((f (deref (car goal)))
           (pred (resolve-functor f)))
      (if (or (pred-control pred) (has-source-vars-p goal))
          (multiple-value-bind (fn frame) (compile-goal-term goal)
            (funcall (the function fn) m frame cont (machine-cp-top m)))
          (funcall (pred-entry pred) m (cdr goal) cont)))))

(defvar *compiled-goals* (make-hash-table :test 'eq :weakness :key :synchronized t)
  "Goal term → (goal-function nvars env extra-vars) for goals that were asked more than once (a
query written as a constant), with the same pre-bound variables EXTRA-VARS each time (NIL: none),
so that they are compiled once.")

(sb-ext:defglobal **last-compiled-goal** (cons nil nil)
  "(goal . entry) of the goal COMPILED-GOAL looked up last, so that repeating a query skips the
table.")

(sb-ext:defglobal **recent-goals** (make-array 16 :initial-element '(nil))
  "(goal . entry) of the last goals compiled, most of them built afresh for one query and never
asked again: a goal is put into *COMPILED-GOALS* when it is asked again while it is still here,
so that the table holds the goals asked repeatedly only.")

(declaim (type (cons fixnum null) **recent-goal-next**))
(sb-ext:defglobal **recent-goal-next** (list 0)
  "The slot of **RECENT-GOALS** the next compiled goal goes to.")

(defun recent-goal-entry (goal &optional (test #'eq))
  "The entry of a goal among **RECENT-GOALS** that is TEST (EQ, or EQUAL for a query built
afresh) to GOAL, or NIL."
  (let ((recent **recent-goals**))
    (declare (type (simple-vector 16) recent))
    (loop for i of-type fixnum below 16
          for slot = (svref recent i)
          when (and (car slot) (funcall test (car slot) goal)) return (cdr slot))))

(defun compiled-goal (goal &optional extra-vars)
  "The goal function, frame and environment of the source GOAL, with variables also for the
symbols EXTRA-VARS (the pre-bound variables of a query, see COMPILE-GOAL-TERM): compiled once
when the same goal object is asked repeatedly with the same EXTRA-VARS (a constant query), else
compiled for this query."
  (flet ((fits (entry) (and entry (equal (fourth entry) extra-vars))))
    (let ((entry (let ((last **last-compiled-goal**))
                   (if (and (eq (car last) goal) goal (fits (cdr last)))
                       (cdr last)
                       (let ((entry (or (let ((kept (gethash goal *compiled-goals*)))
                                          (and (fits kept) kept))
                                        (let ((recent (and goal (recent-goal-entry goal))))
                                          (when (fits recent)
                                            (setf (gethash goal *compiled-goals*) recent)
                                            recent))
                                        ;; the same query built afresh: not kept in the table
                                        (let ((same (and (consp goal) (recent-goal-entry goal #'equal))))
                                          (and (fits same) same)))))
                         (when entry
                           (setf **last-compiled-goal** (cons goal entry)))
                         entry)))))
      (if entry
          (destructuring-bind (fn nvars env &rest more) entry
            (declare (ignore more))
            (let ((frame (make-array (the fixnum nvars))))
              (loop for (sym . i) in env
                    do (setf (svref frame i) (make-pvar sym)))
              (values fn frame env)))
          (multiple-value-bind (fn frame env) (compile-goal-term goal extra-vars)
            (when (consp goal)
              (let ((i (logand (sb-ext:atomic-incf (car **recent-goal-next**)) 15)))
                (setf (svref **recent-goals** i)
                      (cons goal (list fn (length frame) env (copy-list extra-vars))))))
            (values fn frame env))))))

(defun compile-goal-term (goal &optional extra-vars)
  "Compile the term GOAL (its ?symbols being variables) into a goal function; return it, a fresh
frame holding a new variable for each ?symbol, and the alist symbol → frame index."
  (let ((goal (resolve-term goal))
        (*env* '())
        (*nvars* 0)
        (*seen* '()))
    (dolist (v (term-vars goal))
      (var-index v)
      (push v *seen*))
    (dolist (v extra-vars)
      (unless (member v *seen* :test #'eq)
        (var-index v)
        (push v *seen*)))
    (let* ((fn (compile-goal goal))
           (frame (make-array *nvars*)))
      (loop for (sym . i) in *env*
            do (setf (svref frame i) (make-pvar sym)))
      (values fn frame (reverse *env*)))))

;;; Collecting solutions

(defun findall-resume (m index)
  (let ((acc (cp-data m index 0))
        (result (cp-data m index 1))
        (cont (cp-data m index 2)))
    (setf (machine-cp-top m) index)
    (let ((items (funcall (the function (cdr acc)) (reverse (car acc)))))
      (and (not (eq items :fail))
           (unify-terms m result items)
           (funcall (the function cont))))))

(defun compile-collect (template goal result finish)
  "Collect TEMPLATE over every solution of GOAL; (FINISH list) → value for RESULT, or :FAIL."
  (let ((tb (compile-build template))
        (g (compile-goal goal))
        (rb (compile-build result)))
    (declare (type function tb g rb))
    (lambda (m frame cont barrier)
      (declare (ignore barrier))
      (let ((acc (cons '() finish)))
        (push-cp m #'findall-resume acc (funcall rb frame) cont)
        (funcall g m frame
                 (lambda () (push (copy-term-fresh (funcall tb frame)) (car acc)) nil)
                 (machine-cp-top m))))))

(define-control findall (template goal result)
  (compile-collect template goal result #'identity))

(define-control bagof (template goal result)
  (compile-collect template goal result (lambda (items) (or items :fail))))

(define-control setof (template goal result)
  (compile-collect template goal result
                   (lambda (items)
                     (or (remove-duplicates items :test #'equal :from-end t) :fail))))

(define-control forall (condition action)
  (compile-goal `(not (and ,condition (not ,action)))))

(defun every-resume (m index)
  (let ((state (cp-data m index 0))
        (vars (cp-data m index 1))
        (cont (cp-data m index 2)))
    (setf (machine-cp-top m) index)
    (destructuring-bind (failed . values) state
      (and (not failed)
           (or (null values)
               (and (every (lambda (v) (equal v (car values))) (cdr values))
                    (unify-terms m vars (car values))))
           (funcall (the function cont))))))

(define-control every (generator pattern)
  ;; PATTERN must hold for every solution of GENERATOR, and its variables that GENERATOR does
  ;; not bind must take the same values in all of them; they are bound to those values.
  (let* ((free (set-difference (term-vars pattern) (term-vars generator)))
         (g (compile-goal generator))
         (p (compile-goal pattern))
         (vb (compile-build free)))
    (declare (type function g p vb))
    (lambda (m frame cont barrier)
      (declare (ignore barrier))
      (let ((state (list nil))
            (vars (funcall vb frame)))
        (let* ((base (push-cp m #'every-resume state vars cont))
               (above (+ base +cp-size+)))
          (funcall g m frame
                   (lambda ()
                     (let ((h (machine-cp-top m)))
                       (push-cp m (lambda (m index)
                                    (declare (ignore index))
                                    (setf (car state) t)
                                    (cut-to m above)
                                    nil)
                                nil nil nil)
                       (funcall p m frame
                                (lambda ()
                                  (cut-to m h)
                                  (push (resolve-term vars) (cdr state))
                                  nil)
                                (machine-cp-top m))))
                   above))))))
