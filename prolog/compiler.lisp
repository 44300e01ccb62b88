;;;; Compilation of clauses into trees of closures.
;;;;
;;;; A clause becomes a head matcher (M FRAME ARGS) → boolean and a body function
;;;; (M FRAME CONT BARRIER). FRAME is a simple-vector holding the clause instance's variables: a
;;;; variable's first occurrence in the head just stores the caller's term, later occurrences
;;;; unify; variables first seen in the body get fresh PVARs. CONT is the success continuation (a
;;;; function of no arguments); a goal that fails returns NIL. Every call of a continuation or a
;;;; predicate is a tail call, so a deterministic recursion runs in constant Lisp stack. BARRIER
;;;; is the choice-point height a cut in the body returns to.
;;;;
;;;; Heads are matched in the machine's scratch frame, so a clause whose head does not match
;;;; allocates nothing; a clause with a body then gets its own frame, except when the body is a
;;;; single predicate call, which builds its arguments from the scratch frame at once.

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
  (nhead 0 :type fixnum)  ; frame slots 0 .. NHEAD-1 hold the head's variables
  (match nil :type function)
  (arity -1 :type fixnum) ; number of head arguments, -1 when they are not a proper list
  (match-n nil)           ; for ARITY 1 .. 4: matcher (M FRAME A1 ... AN) of the arguments
  (init '() :type list)   ; ((index . name) ...) of body-only variables
  (frameless nil)         ; the body is one predicate call: it runs in the head's frame
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

;;; Closures are made per combination of element kinds, so that the kind dispatch of
;;; MATCH-ELEMENT and BUILD-ELEMENT is folded away when the closure is compiled.

(defmacro with-constant-kinds ((&rest specs) &body body)
  "BODY once per combination of the kinds in SPECS, ((var kinds) ...), with each VAR a constant
in it: the closures BODY makes dispatch on nothing at run time. When KINDS ends in :RUNTIME, the
kinds not listed keep VAR a variable; otherwise the last kind stands for all others."
  (if (null specs)
      `(progn ,@body)
      (destructuring-bind ((var kinds) &rest more) specs
        (let ((inner `(with-constant-kinds ,more ,@body)))
          `(case ,var
             ,@(loop for (k . rest) on kinds
                     collect (cond ((eq k :runtime) `(otherwise ,inner))
                                   (rest `(,k (symbol-macrolet ((,var ,k)) ,inner)))
                                   (t `(otherwise (symbol-macrolet ((,var ,k)) ,inner))))))))))

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
       (1 (let ((y (deref (svref ,frame d))) (x (deref ,x)))
            (cond ((eq x y) t)
                  ;; two different symbols: no need to call the unifier
                  ((and (symbolp x) (symbolp y)) nil)
                  (t (unify-terms ,m y x)))))
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
constant, 2 anonymous, 3 a builder closure, 4 a variable's first occurrence (a new variable
stored in the frame). Updates *SEEN* like COMPILE-BUILD."
  (cond ((anonymous-var-p p) (values 2 nil))
        ((and (source-var-p p) (member p *seen* :test #'eq)) (values 0 (var-index p)))
        ((source-var-p p) (let ((i (var-index p))) (push p *seen*) (values 4 i)))
        ((not (has-source-vars-p p)) (values 1 p))
        (t (values 3 (compile-build p)))))

(defmacro build-element (kind datum frame)
  `(let ((d ,datum))
     (case ,kind
       (0 (svref ,frame d))
       (1 d)
       (2 (make-pvar))
       (4 (setf (svref ,frame d) (make-pvar)))
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
               (with-constant-kinds ((kcar (0 1 2 4 3)) (kcdr (0 1 2 4 3)))
                 (lambda (frame)
                   (declare (type simple-vector frame) (optimize (safety 0)))
                   (let ((a (build-element kcar dcar frame)))
                     (cons a (build-element kcdr dcdr frame))))))))))

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
                 (with-constant-kinds ((kcar (0 1 2 3 5 4)) (kcdr (0 1 2 3 5 4)))
                   (lambda (m frame term)
                     (declare (type simple-vector frame) (optimize (safety 0)))
                     (let ((x (deref term)))
                       (cond ((consp x)
                              (and (match-element kcar dcar m frame (car x))
                                   (match-element kcdr dcdr m frame (cdr x))))
                             ((pvar-p x) (bind-var m x (funcall builder frame)))
                             (t nil)))))))))))

;;; Argument lists: the common case of a proper list of arguments gets one loop instead of a
;;; chain of closures, with variables and atoms handled inline.

(eval-when (:compile-toplevel :load-toplevel :execute)
  (defparameter *unrolled-arities* '(1 2 3 4)
    "Argument counts whose matchers and builders are compiled without a loop."))

(defmacro unrolled-args-matcher (n kinds data suffixes)
  "A matcher of N arguments from the classified elements in the vectors KINDS, DATA, SUFFIXES."
  (let ((ks (loop repeat n collect (gensym "K")))
        (ds (loop repeat n collect (gensym "D")))
        (ss (loop repeat n collect (gensym "S"))))
    `(let (,@(loop for k in ks for i from 0 collect `(,k (aref ,kinds ,i)))
           ,@(loop for d in ds for i from 0 collect `(,d (svref ,data ,i)))
           ,@(loop for s in ss for i from 0 collect `(,s (svref ,suffixes ,i))))
       (declare (type fixnum ,@ks) (type function ,@ss))
       (with-constant-kinds ,(if (<= n 3)
                                 (loop for k in ks repeat 2 collect `(,k (0 1 3 :runtime)))
                                 '())
       (lambda (m frame args)
         (declare (type simple-vector frame) (optimize (safety 0)))
         (let ((a args))
           (block match
             ,@(loop for k in ks for d in ds for s in ss
                     collect `(setf a (deref a))
                     collect `(unless (consp a)
                                (return-from match (and (pvar-p a) (funcall ,s m frame a))))
                     collect `(unless (match-element ,k ,d m frame (car a))
                                (return-from match nil))
                     collect `(setf a (cdr a)))
             (let ((a (deref a)))
               (or (null a) (and (pvar-p a) (bind-var m a nil)))))))))))

(eval-when (:compile-toplevel :load-toplevel :execute)
  (defun elements-form (ks ds kinds data lambda-form)
    "LAMBDA-FORM with the variables KS bound to the elements of the kind vector KINDS and DS to
those of the data vector DATA, and (for up to 3 elements) the first two kinds made constants
where they are common (WITH-CONSTANT-KINDS)."
    `(let (,@(loop for k in ks for i from 0 collect `(,k (aref ,kinds ,i)))
           ,@(loop for d in ds for i from 0 collect `(,d (svref ,data ,i))))
       (declare (type fixnum ,@ks))
       (with-constant-kinds ,(if (<= (length ks) 3)
                                 (loop for k in ks repeat 2 collect `(,k (0 1 3 :runtime)))
                                 '())
         ,lambda-form))))

(defmacro positional-args-matcher (n kinds data)
  "A matcher (M FRAME A1 ... AN) of N arguments passed one by one, from the classified elements
in the vectors KINDS and DATA."
  (let ((ks (loop repeat n collect (gensym "K")))
        (ds (loop repeat n collect (gensym "D")))
        (as (loop repeat n collect (gensym "A"))))
    (elements-form ks ds kinds data
                   `(lambda (m frame ,@as)
                      (declare (type simple-vector frame) (optimize (safety 0)))
                      (and ,@(loop for k in ks for d in ds for a in as
                                   collect `(match-element ,k ,d m frame ,a)))))))


(defun compile-args-match (patterns)
  "Like COMPILE-MATCH for a whole argument list PATTERNS. For a proper list of 1 to 4
patterns, the second value is a matcher (M FRAME A1 ... AN) of the arguments passed one by one."
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
        (macrolet ((by-arity ()
                     `(case k
                        ,@(loop for n in *unrolled-arities*
                                collect `(,n (values
                                              (unrolled-args-matcher ,n kinds data suffixes)
                                              (positional-args-matcher ,n kinds data))))
                        (t
                         (lambda (m frame args)
                           (declare (type simple-vector frame) (optimize (safety 0)))
                           (let ((a args))
                             (dotimes (i k (let ((a (deref a)))
                                             (or (null a) (and (pvar-p a) (bind-var m a nil)))))
                               (setf a (deref a))
                               (unless (consp a)
                                 (return (and (pvar-p a)
                                              (funcall (the function (svref suffixes i))
                                                       m frame a))))
                               (let ((x (car a)))
                                 (unless (match-element (aref kinds i) (svref data i) m frame x)
                                   (return nil)))
                               (setf a (cdr a)))))))))
          (by-arity)))))

(defun classify-args-build (patterns)
  "Kinds and data vectors of BUILD-ELEMENT for the proper argument list PATTERNS all of whose
variables have values, or NIL when PATTERNS is not of that form."
  (unless (or (not (alexandria:proper-list-p patterns)) (null patterns)
              (not (has-source-vars-p patterns))
              (some (lambda (v) (not (member v *seen* :test #'eq))) (term-vars patterns)))
    (classify-elements patterns)))

(defun classify-elements (patterns)
  "Kinds and data vectors of BUILD-ELEMENT for each of the proper list PATTERNS."
  (let* ((k (length patterns))
         (kinds (make-array k :element-type 'fixnum))
         (data (make-array k)))
    (loop for p in patterns
          for i from 0
          do (multiple-value-bind (kind datum) (classify-build-element p)
               (setf (aref kinds i) kind (svref data i) datum)))
    (values kinds data)))

(defun classify-call-args (patterns)
  "Kinds and data vectors of BUILD-ELEMENT for the argument list PATTERNS of a call when it is
a proper list of 1 to 4 elements (a variable's first occurrence makes it), or NIL."
  (when (and (alexandria:proper-list-p patterns) (<= 1 (length patterns) 4))
    (classify-elements patterns)))

(defmacro positional-call (n pred kinds data)
  "A goal function (M FRAME CONT BARRIER) calling PRED's entry for N arguments passed one by
one with the N elements built from KINDS and DATA."
  (let ((ks (loop repeat n collect (gensym "K")))
        (ds (loop repeat n collect (gensym "D")))
        (as (loop repeat n collect (gensym "A")))
        (entry (ecase n (1 'pred-entry1) (2 'pred-entry2) (3 'pred-entry3) (4 'pred-entry4))))
    (elements-form ks ds kinds data
                   `(lambda (m frame cont barrier)
                      (declare (type simple-vector frame) (ignore barrier) (optimize (safety 0)))
                      (let* (,@(loop for k in ks for d in ds for a in as
                                     collect `(,a (build-element ,k ,d frame))))
                        (funcall (,entry ,pred) m ,@as cont))))))

(defun compile-args-build (patterns)
  "Like COMPILE-BUILD for a whole argument list PATTERNS, all of whose variables have values."
  (multiple-value-bind (kinds data) (classify-args-build patterns)
    (if (null kinds)
        (compile-build patterns)
        (let ((k (length kinds)))
          (declare (type (simple-array fixnum (*)) kinds) (type simple-vector data))
          (lambda (frame)
            (declare (type simple-vector frame) (optimize (safety 0)))
            (let ((result '()))
              (loop for i of-type fixnum from (1- k) downto 0
                    do (push (build-element (aref kinds i) (svref data i) frame) result))
              result))))))

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
      (multiple-value-bind (match match-n) (compile-args-match (cdr head))
       (let* ((nhead *nvars*)
             (init (loop for v in (term-vars body)
                         unless (member v *seen* :test #'eq)
                           collect (prog1 (cons (var-index v) v) (push v *seen*))))
             (body-fn (and body (compile-body body)))
             (frameless (and body (null (cdr body)) (plain-call-p (car body))))
             (first (if (consp (cdr head)) (cadr head) '?_)))
        (make-clause :kind (cond ((source-var-p first) 0) ((consp first) 2) (t 1))
                     :key (if (or (source-var-p first) (consp first)) nil first)
                     :nvars *nvars* :nhead nhead :frameless frameless :match match :init init :body body-fn
                     :arity (if (alexandria:proper-list-p (cdr head)) (length (cdr head)) -1)
                     :match-n match-n
                     :source clause))))))

(defun plain-call-p (goal)
  "True when the source GOAL compiles to a call of a predicate (not a control construct): its
goal function reads the frame only to build the call's arguments, before calling."
  (and (consp goal)
       (car goal) (symbolp (car goal)) (not (source-var-p (car goal)))
       (not (pred-control (resolve-functor (car goal))))))

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
               (declare (optimize (safety 0)))
               (funcall first m frame
                        (lambda () (funcall rest m frame cont barrier))
                        barrier))))))

(defun compile-goal (goal)
  "A function (M FRAME CONT BARRIER) proving the source GOAL."
  (cond ((or (source-var-p goal) (pvar-p goal))
         (compile-goal (list 'call goal)))
        ((atom goal)
         (prolog-error "A goal must be a list (functor arg...), got ~s." goal))
        ((source-var-p (car goal))
         (prolog-error "The goal ~s has the variable ~s as its functor; a goal's functor must ~
be a symbol (write (call ~s ...) to call a goal held in a variable)."
                       goal (car goal) (car goal)))
        (t
         (let ((pred (resolve-functor (car goal))))
           (if (pred-control pred)
               (funcall (the function (pred-control pred)) (cdr goal))
               (multiple-value-bind (kinds data) (classify-call-args (cdr goal))
                 (macrolet ((by-arity ()
                              `(case (length kinds)
                                 ,@(loop for n in '(1 2 3 4)
                                         collect `(,n (positional-call ,n pred kinds data))))))
                   (if kinds
                       (by-arity)
                       (let ((build (compile-args-build (cdr goal))))
                         (declare (type function build))
                         (lambda (m frame cont barrier)
                           (declare (ignore barrier))
                           (funcall (pred-entry pred) m (funcall build frame) cont)))))))))))
