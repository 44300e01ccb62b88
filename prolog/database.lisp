;;;; Fact groups, Lisp handlers and facts added at run time.

(in-package :cram-prolog)

(define-condition fact-group-error (prolog-error)
  ((functor :initarg :functor :initform nil :reader fact-group-error-functor)
   (group :initarg :group :initform nil :reader fact-group-error-group)
   (other-group :initarg :other-group :initform nil :reader fact-group-error-other-group))
  (:documentation "A fact group is malformed, or gives clauses to a functor that another group
defines without either group declaring the functor extendable."))

(defstruct (fact-group (:copier nil) (:conc-name group-))
  name (order 0 :type fixnum) extendable functors clauses)

(defvar *fact-groups* (make-hash-table :test 'eq) "Group name → FACT-GROUP.")
(defvar *group-counter* 0 "Registration sequence number of the newest group.")

(defun group-error (group format &rest args)
  (error 'fact-group-error :group group
                           :message (format nil "In fact group ~s: ~?" group format args)))

(defun register-fact-group (name extendable clauses)
  "Define (or redefine, keeping its place in the clause order) the fact group NAME."
  (unless (and name (symbolp name))
    (error 'fact-group-error :group name
                             :message (format nil "A fact group name must be a non-nil symbol, got ~s."
                                              name)))
  (unless (and (listp extendable) (every (lambda (f) (and f (symbolp f))) extendable))
    (group-error name "the extendable functors must be a list of symbols, got ~s." extendable))
  (dolist (c clauses)
    (handler-case (check-clause c)
      (prolog-error (e) (group-error name "~a" e))))
  (with-database-lock ()
    (let ((functors (remove-duplicates (mapcar #'caar clauses) :from-end t))
          (old (gethash name *fact-groups*)))
      (dolist (f functors)
        (let ((pred (gethash f *predicates*)))
          (when (and pred (or (pred-native pred) (pred-control pred)))
            (error 'fact-group-error
                   :functor f :group name :other-group nil
                   :message (format nil "Fact group ~s defines clauses for ~s, a built-in ~
predicate, which cannot be redefined or extended; choose another name." name f)))
          (when pred
            (dolist (source (pred-sources pred))
              (progn
                (unless (or (eq (car source) name)
                            (member f extendable)
                            (and old (member f (group-functors old))))
                  (error 'fact-group-error
                         :functor f :group name :other-group (car source)
                         :message (format nil "Fact group ~s gives clauses to ~s, which fact group ~s ~
already defines, but does not list ~s among its extendable functors: write (def-fact-group ~s (~s ...) ...)."
                                          name f (car source) f name f))))))))
      (when old
        (dolist (f (group-functors old))
          (let ((pred (ensure-pred f)))
            (setf (pred-sources pred) (remove name (pred-sources pred) :key #'car))
            (invalidate-pred pred))))
      (let ((group (make-fact-group :name name
                                    :order (if old (group-order old) (incf *group-counter*))
                                    :extendable extendable :functors functors
                                    :clauses clauses)))
        (setf (gethash name *fact-groups*) group)
        (dolist (f functors)
          (let ((pred (ensure-pred f)))
            (setf (pred-sources pred)
                  (sort (cons (cons name (remove f clauses :key #'caar :test-not #'eq))
                              (copy-list (pred-sources pred)))
                        #'< :key (lambda (s) (group-order (gethash (car s) *fact-groups*)))))
            (setf (pred-warned pred) nil)
            (invalidate-pred pred))))
      name)))

(defmacro def-fact-group (name (&rest extendable-functors) &body clauses)
  "Define the fact group NAME from clauses (<- head goal...). A functor that another group
already defines may get clauses here only if this group lists it among EXTENDABLE-FUNCTORS, as
in CRAM; otherwise a FACT-GROUP-ERROR names both groups and the functor. Redefining a group
replaces its clauses and keeps its place (and its right to the functors it defined): clauses
are ordered by group registration, then textually."
  (let ((forms (mapcar (lambda (c)
                         (unless (and (consp c) (symbolp (car c)) (string= (symbol-name (car c)) "<-"))
                           (error 'fact-group-error
                                  :group name
                                  :message (format nil "In fact group ~s: expected a clause (<- head goal...), got ~s."
                                                   name c)))
                         (cdr c))
                       clauses)))
    `(register-fact-group ',name ',extendable-functors ',forms)))

(defmacro <- (head &body goals)
  "A clause; only valid inside DEF-FACT-GROUP."
  (declare (ignore goals))
  `(error 'prolog-error
          :message ,(format nil "The clause for ~s is outside DEF-FACT-GROUP; <- is only valid inside it."
                            head)))

(defun remove-fact-group (name)
  "Remove the fact group NAME and its clauses. True when it existed."
  (with-database-lock ()
    (let ((old (gethash name *fact-groups*)))
      (when old
        (dolist (f (group-functors old))
          (let ((pred (ensure-pred f)))
            (setf (pred-sources pred) (remove name (pred-sources pred) :key #'car))
            (invalidate-pred pred)))
        (remhash name *fact-groups*)
        t))))

(defun fact-group-names ()
  "The names of the defined fact groups in registration order."
  (with-database-lock ()
    (mapcar #'group-name
            (sort (alexandria:hash-table-values *fact-groups*) #'< :key #'group-order))))

(defun fact-group-clauses (name)
  "The clauses (head goal...) of the fact group NAME; an error when there is no such group."
  (let ((group (gethash name *fact-groups*)))
    (unless group
      (error 'fact-group-error :group name
                               :message (format nil "There is no fact group named ~s." name)))
    (group-clauses group)))

(defun predicate-clauses (functor)
  "Every clause (head goal...) of FUNCTOR in the order they are tried."
  (let ((pred (gethash functor *predicates*)))
    (and pred (append (loop for (nil . cs) in (pred-sources pred) append cs)
                      (pred-dynamic pred)))))

;;; Facts added at run time

(defun add-fact (fact)
  "Add the ground or non-ground FACT (functor arg...) after the clauses of its functor."
  (unless (and (consp fact) (car fact) (symbolp (car fact)) (not (is-var (car fact))))
    (prolog-error "ADD-FACT expects a term (functor arg...), got ~s." fact))
  (with-database-lock ()
    (let ((pred (ensure-pred (car fact))))
      (setf (pred-dynamic pred) (append (pred-dynamic pred) (list (list fact))))
      (invalidate-pred pred)
      fact)))

(defun remove-facts (pattern)
  "Remove the facts added with ADD-FACT that unify with PATTERN; return how many."
  (unless (and (consp pattern) (car pattern) (symbolp (car pattern)))
    (prolog-error "REMOVE-FACTS expects a term (functor arg...), got ~s." pattern))
  (with-database-lock ()
    (let* ((pred (ensure-pred (car pattern)))
           (old (pred-dynamic pred))
           (new (remove-if (lambda (c) (nth-value 1 (unify pattern (car c)))) old)))
      (setf (pred-dynamic pred) new)
      (invalidate-pred pred)
      (- (length old) (length new)))))

;;; Handlers

(defun set-prolog-handler (name function)
  (unless (and name (symbolp name))
    (prolog-error "A Prolog handler name must be a non-nil symbol, got ~s." name))
  (with-database-lock ()
    (let ((pred (ensure-pred name)))
      (setf (pred-handler pred) function
            (pred-warned pred) nil)
      (invalidate-pred pred)
      name)))

(defun remove-prolog-handler (name)
  "Remove the Lisp handler of the predicate NAME."
  (with-database-lock ()
    (let ((pred (gethash name *predicates*)))
      (when pred
        (setf (pred-handler pred) nil)
        (invalidate-pred pred)
        t))))

(defmacro def-prolog-handler (name (bindings-var &rest lambda-list) &body body)
  "Define the predicate NAME in Lisp. BODY runs with BINDINGS-VAR bound to the binding alist
and LAMBDA-LIST destructuring the goal's arguments, with their bound variables substituted and
unbound ones appearing as ?symbols. It returns a (lazy) list of binding alists, one per
solution, binding those ?symbols. Solutions are taken lazily, one per backtracking step. When
the handler returns no solution (or the goal does not fit LAMBDA-LIST), NAME's clauses from fact
groups, if any, are tried instead."
  (let ((args (gensym "ARGS")))
    (multiple-value-bind (min max) (lambda-list-arity lambda-list)
      `(set-prolog-handler
        ',name
        (lambda (,bindings-var &rest ,args)
          (declare (ignorable ,bindings-var))
          (let ((n (length ,args)))
            (when (and (>= n ,min) ,(if max `(<= n ,max) t))
              (destructuring-bind ,lambda-list ,args ,@body))))))))

(defun handler-view (args)
  "ARGS resolved with each unbound variable replaced by a distinct ?symbol; second value the
alist symbol → variable."
  (let ((view '()))
    (values
     (resolve-term args
                   (lambda (v)
                     (or (car (rassoc v view :test #'eq))
                         (let ((sym (make-symbol (format nil "?_G~d" (1+ (length view))))))
                           (push (cons sym v) view)
                           sym))))
     view)))

(defun solution-term (value view)
  "VALUE from a handler's binding alist as a run-time term: view symbols become their variables,
other ?symbols fresh variables."
  (let ((fresh '()))
    (substitute-symbols value
                        (lambda (x)
                          (or (cdr (assoc x view :test #'eq))
                              (cdr (assoc x fresh :test #'eq))
                              (let ((v (make-pvar x))) (push (cons x v) fresh) v))))))

(defun apply-handler-solution (m solution view)
  (loop for (sym . var) in view
        for value = (var-value sym solution)
        always (or (eq value sym)
                   (unify-terms m var (solution-term value view)))))

(defun handler-retry (m index)
  (let* ((cell (cp-data m index 0))
         (view (cp-data m index 1))
         (cont (cp-data m index 2))
         (next (lazy-cdr cell)))
    (if (null next)
        (progn (setf (machine-cp-top m) index) nil)
        (progn (setf (cp-data m index 0) next)
               (and (apply-handler-solution m (car next) view)
                    (funcall (the function cont)))))))

(defun make-handler-entry (pred handler clause-entry)
  (declare (ignore pred))
  (lambda (m args cont)
    (count-step m)
    (multiple-value-bind (view-args view) (handler-view args)
      (let ((solutions (and (alexandria:proper-list-p view-args)
                            (apply handler nil view-args))))
        (cond (solutions
               (push-cp m #'handler-retry solutions view cont)
               (and (apply-handler-solution m (car solutions) view)
                    (funcall (the function cont))))
              (clause-entry (funcall (the function clause-entry) m args cont))
              (t nil))))))
