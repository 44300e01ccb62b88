;;;; Compilation of clauses into trees of closures.
;;;;
;;;; A clause becomes a head matcher (M FRAME ARGS) → boolean and a body function
;;;; (M FRAME CONT BARRIER). FRAME is a simple-vector holding the clause instance's variables: a
;;;; variable's first occurrence in the head just stores the caller's term, later occurrences
;;;; unify; variables first seen in the body get fresh PVARs. CONT is the success continuation (a
;;;; function of no arguments); a goal that fails returns NIL. Every call of a continuation or a
;;;; predicate is a tail call, so a deterministic recursion runs in constant Lisp stack. BARRIER
;;;; is the choice-point height a cut in the body returns to.

(in-package :cram-prolog)

(declaim (optimize (speed 3) (safety 1) (debug 0)))

(defvar *env* nil "Alist variable symbol → frame index, while compiling one clause or goal.")
(defvar *nvars* 0 "Number of frame slots allocated while compiling.")
(defvar *seen* '() "Variables that already have a value in the frame at this point.")

(defstruct (clause (:copier nil))
  "A compiled clause."
  (kind 0 :type fixnum)   ; first argument: 0 variable/none, 1 atom, 2 cons
  (key nil)               ; the atom when KIND is 1
  (nvars 0 :type fixnum)
  (match nil :type function)
  (init '() :type list)   ; ((index . name) ...) of body-only variables
  (body nil)              ; NIL for a fact
  (source nil))

(declaim (inline anonymous-var-p))
(defun anonymous-var-p (x)
  (and (symbolp x) x
       (let ((name (symbol-name x)))
         (and (= (length name) 2) (char= (char name 0) #\?) (char= (char name 1) #\_)))))

(defun source-var-p (x)
  (is-var x))

(defun has-source-vars-p (x)
  (loop
    (cond ((source-var-p x) (return t))
          ((consp x) (when (has-source-vars-p (car x)) (return t))
           (setf x (cdr x)))
          (t (return nil)))))

(defun term-vars (term)
  "The distinct ?symbols of TERM (without ?_) in order of first occurrence."
  (let ((vars '()))
    (labels ((walk (x)
               (loop
                 (cond ((anonymous-var-p x) (return))
                       ((source-var-p x) (pushnew x vars :test #'eq) (return))
                       ((consp x) (walk (car x)) (setf x (cdr x)))
                       (t (return))))))
      (walk term))
    (nreverse vars)))

(defun substitute-symbols (term function)
  "TERM with every ?symbol replaced by (FUNCTION symbol); unchanged parts are shared. Walks
list spines iteratively."
  (cond ((source-var-p term) (funcall (the function function) term))
        ((atom term) term)
        (t (let ((items '()) (x term) (changed nil) (tail nil))
             (loop
               (let ((a (substitute-symbols (car x) function)))
                 (push a items)
                 (unless (eq a (car x)) (setf changed t)))
               (let ((d (cdr x)))
                 (if (and (consp d) (not (source-var-p d)))
                     (setf x d)
                     (progn (setf tail (substitute-symbols d function))
                            (unless (eq tail d) (setf changed t))
                            (return)))))
             (if changed
                 (let ((result tail))
                   (dolist (a items result) (setf result (cons a result))))
                 term)))))

(defun var-index (sym)
  (or (cdr (assoc sym *env* :test #'eq))
      (prog1 *nvars*
        (push (cons sym *nvars*) *env*)
        (incf *nvars*))))

(defun atom-matcher (p)
  (if (or (symbolp p) (typep p 'fixnum) (characterp p))
      (lambda (m frame term)
        (declare (ignore frame))
        (let ((x (deref term)))
          (cond ((eq x p) t)
                ((pvar-p x) (bind-var m x p))
                (t nil))))
      (lambda (m frame term)
        (declare (ignore frame))
        (let ((x (deref term)))
          (if (pvar-p x) (bind-var m x p) (equal x p))))))

(defun simple-atom-p (p)
  (and (atom p) (not (source-var-p p))))

;;; Pattern elements classified for inline matching: KIND 0 store a first occurrence, 1 unify
;;; with a variable's value, 2 anonymous, 3 EQ-comparable atom, 5 other atom, 4 a matcher closure.

(defun classify-match-element (p)
  "Kind and datum of the source pattern P for MATCH-ELEMENT; updates *SEEN* like COMPILE-MATCH."
  (cond ((anonymous-var-p p) (values 2 nil))
        ((source-var-p p)
         (let ((i (var-index p)))
           (if (member p *seen* :test #'eq)
               (values 1 i)
               (progn (push p *seen*) (values 0 i)))))
        ((and (simple-atom-p p) (or (symbolp p) (typep p 'fixnum) (characterp p))) (values 3 p))
        ((simple-atom-p p) (values 5 p))
        (t (values 4 (compile-match p)))))

(defmacro match-element (kind datum m frame x)
  "Inline match of the run-time term X against a classified pattern element."
  `(let ((d ,datum))
     (case ,kind
       (0 (setf (svref ,frame d) ,x) t)
       (1 (unify-terms ,m (svref ,frame d) ,x))
       (2 t)
       (3 (let ((x (deref ,x)))
            (cond ((eq x d) t)
                  ((pvar-p x) (bind-var ,m x d))
                  (t nil))))
       (5 (let ((x (deref ,x)))
            (if (pvar-p x) (bind-var ,m x d) (equal x d))))
       (t (funcall (the function d) ,m ,frame ,x)))))

(defun classify-build-element (p)
  "Kind and datum of source pattern P for BUILD-ELEMENT: 0 a variable with a value, 1 a
constant, 2 anonymous, 3 a builder closure."
  (cond ((anonymous-var-p p) (values 2 nil))
        ((and (source-var-p p) (member p *seen* :test #'eq)) (values 0 (var-index p)))
        ((not (has-source-vars-p p)) (values 1 p))
        (t (values 3 (compile-build p)))))

(defmacro build-element (kind datum frame)
  `(let ((d ,datum))
     (case ,kind
       (0 (svref ,frame d))
       (1 d)
       (2 (make-pvar))
       (t (funcall (the function d) ,frame)))))

(defun compile-build (p)
  "A function of the frame building the run-time term for source pattern P."
  (cond ((anonymous-var-p p) (lambda (frame) (declare (ignore frame)) (make-pvar)))
        ((source-var-p p)
         (let ((i (var-index p)))
           (declare (type fixnum i))
           (if (member p *seen* :test #'eq)
               (lambda (frame) (svref frame i))
               (progn (push p *seen*)
                      (lambda (frame) (setf (svref frame i) (make-pvar p)))))))
        ((not (has-source-vars-p p)) (lambda (frame) (declare (ignore frame)) p))
        (t (multiple-value-bind (kcar dcar) (classify-build-element (car p))
             (multiple-value-bind (kcdr dcdr) (classify-build-element (cdr p))
               (declare (type fixnum kcar kcdr))
               (lambda (frame)
                 (declare (type simple-vector frame))
                 (let ((a (build-element kcar dcar frame)))
                   (cons a (build-element kcdr dcdr frame)))))))))

(defun compile-match (p)
  "A function (M FRAME TERM) unifying the run-time TERM with source pattern P."
  (cond ((anonymous-var-p p) (lambda (m frame term) (declare (ignore m frame term)) t))
        ((source-var-p p)
         (let ((i (var-index p)))
           (declare (type fixnum i))
           (if (member p *seen* :test #'eq)
               (lambda (m frame term) (unify-terms m (svref frame i) term))
               (progn (push p *seen*)
                      (lambda (m frame term)
                        (declare (ignore m))
                        (setf (svref frame i) term)
                        t)))))
        ((atom p) (atom-matcher p))
        ((not (has-source-vars-p p)) (lambda (m frame term)
                                       (declare (ignore frame))
                                       (unify-terms m p term)))
        (t (let* ((seen *seen*)
                  (builder (compile-build p)))
             (declare (type function builder))
             (setf *seen* seen)
             (multiple-value-bind (kcar dcar) (classify-match-element (car p))
               (multiple-value-bind (kcdr dcdr) (classify-match-element (cdr p))
                 (declare (type fixnum kcar kcdr))
                 (lambda (m frame term)
                   (declare (type simple-vector frame))
                   (let ((x (deref term)))
                     (cond ((consp x)
                            (and (match-element kcar dcar m frame (car x))
                                 (match-element kcdr dcdr m frame (cdr x))))
                           ((pvar-p x) (bind-var m x (funcall builder frame)))
                           (t nil))))))))))

;;; Argument lists: the common case of a proper list of arguments gets one loop instead of a
;;; chain of closures, with variables and atoms handled inline.

(defun compile-args-match (patterns)
  "Like COMPILE-MATCH for a whole argument list PATTERNS."
  (if (or (not (alexandria:proper-list-p patterns)) (null patterns))
      (compile-match patterns)
      (let* ((k (length patterns))
             (kinds (make-array k :element-type 'fixnum))
             (data (make-array k))
             (suffixes (make-array k)))
        (loop for p in patterns
              for tail on patterns
              for i from 0
              do (let ((seen *seen*))
                   ;; the matcher of the remaining arguments, for an argument list ending in a
                   ;; variable (goals written (functor . ?args))
                   (setf (svref suffixes i) (compile-match tail))
                   (setf *seen* seen))
                 (multiple-value-bind (kind datum) (classify-match-element p)
                   (setf (aref kinds i) kind (svref data i) datum)))
        (lambda (m frame args)
          (declare (type simple-vector frame))
          (let ((a args))
            (dotimes (i k (let ((a (deref a)))
                            (or (null a) (and (pvar-p a) (bind-var m a nil)))))
              (setf a (deref a))
              (unless (consp a)
                (return (and (pvar-p a) (funcall (the function (svref suffixes i)) m frame a))))
              (let ((x (car a)))
                (unless (match-element (aref kinds i) (svref data i) m frame x)
                  (return nil)))
              (setf a (cdr a))))))))

(defun compile-args-build (patterns)
  "Like COMPILE-BUILD for a whole argument list PATTERNS, all of whose variables have values."
  (if (or (not (alexandria:proper-list-p patterns)) (null patterns)
          (not (has-source-vars-p patterns))
          (some (lambda (v) (not (member v *seen* :test #'eq))) (term-vars patterns)))
      (compile-build patterns)
      (let* ((k (length patterns))
             (kinds (make-array k :element-type 'fixnum))
             (data (make-array k)))
        (loop for p in patterns
              for i from 0
              do (multiple-value-bind (kind datum) (classify-build-element p)
                   (setf (aref kinds i) kind (svref data i) datum)))
        (lambda (frame)
          (declare (type simple-vector frame))
          (let ((result '()))
            (loop for i of-type fixnum from (1- k) downto 0
                  do (push (build-element (aref kinds i) (svref data i) frame) result))
            result)))))

(defun check-clause (clause)
  (unless (and (consp clause) (consp (car clause)) (car (car clause))
               (symbolp (car (car clause))) (not (source-var-p (car (car clause)))))
    (prolog-error "A clause must be (head goal...) with a head (functor arg...) whose functor ~
is a symbol, got ~s." clause)))

(defun compile-clause (clause)
  "Compile CLAUSE, a list (head . body) of source terms, into a CLAUSE structure."
  (check-clause clause)
  (let ((*env* '())
        (*nvars* 0)
        (*seen* '()))
    (destructuring-bind (head . body) clause
      (let* ((match (compile-args-match (cdr head)))
             (init (loop for v in (term-vars body)
                         unless (member v *seen* :test #'eq)
                           collect (prog1 (cons (var-index v) v) (push v *seen*))))
             (body-fn (and body (compile-body body)))
             (first (if (consp (cdr head)) (cadr head) '?_)))
        (make-clause :kind (cond ((source-var-p first) 0) ((consp first) 2) (t 1))
                     :key (if (or (source-var-p first) (consp first)) nil first)
                     :nvars *nvars* :match match :init init :body body-fn
                     :source clause)))))

(defun compile-body (goals)
  "A goal function running the conjunction GOALS."
  (cond ((null goals) (lambda (m frame cont barrier)
                        (declare (ignore m frame barrier) (type function cont))
                        (funcall cont)))
        ((null (cdr goals)) (compile-goal (car goals)))
        (t (let ((first (compile-goal (car goals)))
                 (rest (compile-body (cdr goals))))
             (declare (type function first rest))
             (lambda (m frame cont barrier)
               (funcall first m frame
                        (lambda () (funcall rest m frame cont barrier))
                        barrier))))))

(defun compile-goal (goal)
  "A function (M FRAME CONT BARRIER) proving the source GOAL."
  (cond ((or (source-var-p goal) (pvar-p goal))
         (compile-goal (list 'call goal)))
        ((atom goal)
         (prolog-error "A goal must be a list (functor arg...), got ~s." goal))
        (t
         (let ((pred (resolve-functor (car goal))))
           (if (pred-control pred)
               (funcall (the function (pred-control pred)) (cdr goal))
               (let ((build (compile-args-build (cdr goal))))
                 (declare (type function build))
                 (lambda (m frame cont barrier)
                   (declare (ignore barrier))
                   (funcall (pred-entry pred) m (funcall build frame) cont))))))))

;;; Running clauses

(declaim (inline first-arg-of clause-compatible-p))
(defun first-arg-of (args)
  "The dereferenced first argument of the run-time argument list ARGS, or +UNBOUND+ when unknown."
  (let ((args (deref args)))
    (if (consp args)
        (let ((a (deref (car args))))
          (if (pvar-p a) +unbound+ a))
        +unbound+)))

(defun clause-compatible-p (clause a)
  (declare (type clause clause))
  (case (clause-kind clause)
    (0 t)
    (1 (or (eq a +unbound+)
           (and (atom a)
                (let ((k (clause-key clause)))
                  (or (eq a k) (and (not (symbolp k)) (equal a k)))))))
    (t (or (eq a +unbound+) (consp a)))))

(defun next-compatible (clauses a)
  (loop for tail on clauses
        when (clause-compatible-p (car tail) a) return tail))

(defvar +empty-frame+ (vector))

(declaim (inline run-clause))
(defun run-clause (m clause args cont barrier)
  (declare (type clause clause))
  (let* ((n (clause-nvars clause))
         (frame (if (zerop n) +empty-frame+ (make-array n))))
    (when (funcall (clause-match clause) m frame args)
      (loop for (i . name) in (clause-init clause)
            do (setf (svref frame i) (make-pvar name)))
      (let ((body (clause-body clause)))
        (if body
            (funcall (the function body) m frame cont barrier)
            (funcall (the function cont)))))))

(defun retry-clauses (m index)
  (let* ((rest (cp-data m index 0))
         (args (cp-data m index 1))
         (cont (cp-data m index 2))
         (next (next-compatible (cdr rest) (first-arg-of args))))
    (if next
        (setf (cp-data m index 0) next)
        (setf (machine-cp-top m) index))
    (run-clause m (car rest) args cont index)))

(defun try-clauses (m clauses args cont)
  "Run the CLAUSES whose first argument can match ARGS, leaving a choice point for the rest."
  (let* ((a (first-arg-of args))
         (tail (next-compatible clauses a)))
    (when tail
      (let ((rest (next-compatible (cdr tail) a))
            (barrier (machine-cp-top m)))
        (when rest
          (push-cp m #'retry-clauses rest args cont))
        (run-clause m (car tail) args cont barrier)))))

(defparameter *index-threshold* 8
  "Predicates with at least this many clauses get a first-argument index.")

(defun make-clauses-entry (clauses)
  "The entry function running CLAUSES, indexed on the first argument when they are many."
  (if (< (length clauses) *index-threshold*)
      (lambda (m args cont) (try-clauses m clauses args cont))
      (let ((table (make-hash-table
                    ;; EQUAL and EQL agree on every key but strings, bit vectors and pathnames
                    :test (if (some (lambda (c) (and (= 1 (clause-kind c))
                                                     (typep (clause-key c)
                                                            '(or string bit-vector pathname))))
                                    clauses)
                              'equal 'eql)))
            (var-clauses (remove-if-not (lambda (c) (= 0 (clause-kind c))) clauses))
            (cons-clauses (remove 1 clauses :key #'clause-kind)))
        ;; bucket per atom key: clauses with that key or a variable first argument, in order
        (let ((vars-so-far '()))
          (dolist (c clauses)
            (case (clause-kind c)
              (0 (push c vars-so-far)
               (maphash (lambda (k bucket) (setf (gethash k table) (cons c bucket))) table))
              (1 (let ((bucket (gethash (clause-key c) table :none)))
                   (setf (gethash (clause-key c) table)
                         (cons c (if (eq bucket :none) vars-so-far bucket))))))))
        (maphash (lambda (k bucket) (setf (gethash k table) (reverse bucket))) table)
        (lambda (m args cont)
          (let ((a (first-arg-of args)))
            (try-clauses m (cond ((eq a +unbound+) clauses)
                                 ((consp a) cons-clauses)
                                 (t (gethash a table var-clauses)))
                         args cont))))))
