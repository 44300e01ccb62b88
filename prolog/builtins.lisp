;;;; Native built-in predicates: comparisons, lists, calls into Lisp, Lisp data.

(in-package :cram-prolog)

(declaim (optimize (speed 3) (safety 1) (debug 0)))

(defun register-native (name function &optional positional)
  "Make FUNCTION, (lambda (m args cont)), the definition of the predicate NAME. POSITIONAL, when
given, is (n . entry): ENTRY (lambda (m a1 ... an cont)) serves calls with N arguments."
  (with-database-lock ()
    (let ((pred (ensure-pred name)))
      (setf (pred-native pred) function
            (pred-native-positional pred) positional)
      (setf (gethash (symbol-name name) *builtin-names*) pred)
      (invalidate-pred pred)
      name)))

(defmacro def-native-predicate (name (m cont &rest lambda-list) &body body)
  "Define the predicate NAME natively. LAMBDA-LIST (required, &optional, &rest parameters) is
bound to the goal's run-time argument terms, undereferenced; a goal of another length fails. M
is the machine, CONT the success continuation. BODY must end by returning
(SOLVE-CONTINUE CONT) after a success (in tail position) or NIL for failure; it may bind
variables with (UNIFY-TERMS M a b) and read them with DEREF-TERM or RESOLVE-TERM."
  (let* ((args (gensym "ARGS")) (block (gensym "NATIVE"))
         (optional-at (position '&optional lambda-list))
         (rest-at (position '&rest lambda-list))
         (required (subseq lambda-list 0 (or optional-at rest-at (length lambda-list))))
         (optional (and optional-at (subseq lambda-list (1+ optional-at) rest-at)))
         (rest (and rest-at (nth (1+ rest-at) lambda-list))))
    `(register-native
      ',name
      (lambda (,m ,args ,cont)
        (declare (ignorable ,m ,cont) (type function ,cont))
        (block ,block
          (let* (,@(loop for r in required
                         collect `(,r (let ((s (deref ,args)))
                                        (unless (consp s) (return-from ,block nil))
                                        (setf ,args (cdr s))
                                        (car s))))
                 ,@(loop for o in optional
                         for (var default) = (if (consp o) o (list o nil))
                         collect `(,var (let ((s (deref ,args)))
                                          (if (consp s)
                                              (progn (setf ,args (cdr s)) (car s))
                                              ,default))))
                 ,@(when rest `((,rest ,args))))
            ,@(unless rest `((unless (null (deref ,args)) (return-from ,block nil))))
            ,@body)))
      ;; only required arguments: calls with that many take them one by one
      ,@(when (and (null optional-at) (null rest-at) (<= 1 (length required) 4))
          `((cons ,(length required)
                  (lambda (,m ,@required ,cont)
                    (declare (ignorable ,m ,cont) (type function ,cont))
                    ,@body)))))))

(defmacro solve-continue (cont)
  "Inside DEF-NATIVE-PREDICATE: succeed, continuing with the rest of the proof."
  `(funcall (the function ,cont)))

(defun lisp-argument (term)
  "TERM resolved for a call into Lisp: unbound variables appear as their ?symbols."
  (resolve-term term (lambda (v) (declare (ignore v)) (make-symbol "?_"))))

(defvar *lisp-error-propagating-functions* (make-hash-table :test 'eq :synchronized t)
  "Names of the functions registered with PROPAGATE-LISP-ERRORS.")

(sb-ext:defglobal **propagating-names** #()
  "The names of *LISP-ERROR-PROPAGATING-FUNCTIONS* as a vector, read without a lock.")

(defun propagate-lisp-errors (&rest function-names)
  "Declare that errors signalled by the functions named FUNCTION-NAMES (symbols naming global
functions) propagate out of the Prolog query when LISP-FUN or LISP-PRED calls them, whatever
*BREAK-ON-LISP-ERRORS* says. The rule: a predicate that changes the world (an assert, retract
or simulation step, as CRAM's Bullet-world assert handlers) reports bad input with a Lisp error;
a query predicate, whose failure is the documented answer, keeps warning and failing.
Returns FUNCTION-NAMES."
  (dolist (name function-names function-names)
    (check-type name symbol)
    (setf (gethash name *lisp-error-propagating-functions*) t)
    (setf **propagating-names**
          (coerce (loop for n being the hash-keys of *lisp-error-propagating-functions* collect n)
                  'simple-vector))))

(defun lisp-errors-propagate-p (function)
  "True when errors from FUNCTION (a function object or a symbol) propagate out of queries. A
function object counts when a registered name holds it now (looked up without taking a lock)."
  (cond ((symbolp function) (values (gethash function *lisp-error-propagating-functions*)))
        ((functionp function)
         (let ((names **propagating-names**))
           (declare (type simple-vector names))
           (loop for name across names
                   thereis (and (fboundp name) (eq (symbol-function name) function)))))
        (t nil)))

(defun call-lisp (function args)
  "Apply FUNCTION to ARGS. Returns (values result t), or, when it signals an error,
*BREAK-ON-LISP-ERRORS* is NIL and FUNCTION was not registered with PROPAGATE-LISP-ERRORS,
warns and returns (values nil nil)."
  (if (or *break-on-lisp-errors* (lisp-errors-propagate-p function))
      (values (apply function args) t)
      (handler-case (values (apply function args) t)
        (error (e)
          (warn "Lisp error in a Prolog goal calling ~s on ~s: ~a; the goal fails."
                function args e)
          (values nil nil)))))

(sb-ext:defglobal **function-cache** (make-array 16 :initial-element nil)
  "Direct-mapped cache of (symbol . function) for symbols found to name ordinary functions.")

(defun named-function (symbol)
  "The function SYMBOL names when it names one that is not a macro or special operator, else
NIL. A cached entry is valid while SYMBOL's definition is still the same function object."
  (declare (type symbol symbol))
  (let* ((cache **function-cache**)
         (i (logand (sxhash symbol) 15))
         (entry (svref cache i)))
    (if (and entry (eq (car entry) symbol) (fboundp symbol)
             (eq (symbol-function symbol) (cdr entry)))
        (cdr entry)
        (when (and (fboundp symbol) (not (macro-function symbol))
                   (not (special-operator-p symbol)))
          (let ((function (symbol-function symbol)))
            (setf (svref cache i) (cons symbol function))
            function)))))

(defun function-designator (term goal)
  (let ((f (deref term)))
    (when (functionp f)
      (return-from function-designator f))
    (when (symbolp f)
      (let ((function (named-function f)))
        (when function
          (return-from function-designator function))))
    (setf f (lisp-argument f))
    (cond ((functionp f) f)
          ((and (symbolp f) (fboundp f) (not (macro-function f)) (not (special-operator-p f))) f)
          ((and (consp f) (eq (car f) 'function) (symbolp (second f))) (second f))
          ((and (consp f) (eq (car f) 'lambda)) (coerce f 'function))
          (t (prolog-error "~s needs a function (a function object or the name of a defined ~
function), got ~s." goal f)))))

;;; Comparison and type tests

(def-native-predicate bound (m cont x)
  (unless (pvar-p (deref x)) (solve-continue cont)))

(def-native-predicate ground (m cont x)
  (when (term-ground-p x) (solve-continue cont)))

(def-native-predicate == (m cont a b)
  (when (unify-terms m a b) (solve-continue cont)))

(def-native-predicate equal (m cont a b)
  (when (equal (resolve-term a) (resolve-term b)) (solve-continue cont)))

(declaim (inline comparable-p))
(defun comparable-p (x)
  (and (realp x) (not (and (floatp x) (sb-ext:float-nan-p x)))))

(defun comparison-error (name x y)
  "Signal the PROLOG-ERROR of the comparison (NAME X Y) whose arguments are not both numbers."
  (flet ((shown (v) (if (pvar-p v) "?_" (format nil "~s" (lisp-argument v))))
         (described (v)
           (cond ((pvar-p v) "an unbound variable")
                 ((and (floatp v) (sb-ext:float-nan-p v)) "NaN")
                 (t (format nil "~s" (lisp-argument v))))))
    (prolog-error "(~a ~a ~a): ~a compares two real numbers (not NaN), but ~{~a~^ and ~}."
                  name (shown x) (shown y) name
                  (append (unless (comparable-p x)
                            (list (format nil "the first argument is ~a" (described x))))
                          (unless (comparable-p y)
                            (list (format nil "the second argument is ~a" (described y))))))))

(macrolet ((compare (name op)
             `(def-native-predicate ,name (m cont a b)
                (let ((x (deref a)) (y (deref b)))
                  (if (and (comparable-p x) (comparable-p y))
                      (when (,op x y) (solve-continue cont))
                      (comparison-error ',name x y))))))
  (compare < <) (compare > >) (compare <= <=) (compare >= >=))

;;; Lists

(defun member-retry (m index)
  (let* ((x (cp-data m index 0))
         (cell (cp-data m index 1))
         (cont (cp-data m index 2))
         (next (if (cut:lazy-tail-p (cdr cell)) (lazy-cdr cell) (deref (cdr cell)))))
    (cond ((consp next)
           (setf (cp-data m index 1) next)
           (and (unify-terms m x (car next)) (funcall (the function cont))))
          (t (setf (machine-cp-top m) index) nil))))

(defun unify-each (m term values cont)
  "For a native predicate: unify TERM with each element of the list or lazy list VALUES in turn,
continuing with CONT after each; later elements are reached by backtracking (and computed only
then). Returns like a native predicate's body."
  (let ((l (deref values)))
    (when (consp l)
      (push-cp m #'member-retry term l cont)
      (and (unify-terms m term (car l)) (funcall (the function cont))))))

(def-native-predicate member (m cont x list)
  ;; works on lists and on lazy lists, computing their elements only as far as needed
  (unify-each m x list cont))

(defun list-value (term goal)
  "The proper (forced if lazy) Lisp list TERM denotes; an error naming GOAL otherwise."
  (let ((l (resolve-term term)))
    (unless (alexandria:proper-list-p (if (consp l) (force-ll l) l))
      (prolog-error "~s needs a proper list, got ~s." goal l))
    l))

(def-native-predicate length (m cont list n)
  (let ((l (deref list)))
    (if (pvar-p l)
        (let ((k (deref n)))
          (unless (typep k '(integer 0))
            (prolog-error "LENGTH needs a bound list or a non-negative integer length, got ~s and ~s."
                          (lisp-argument list) (lisp-argument n)))
          (when (unify-terms m l (loop repeat k collect (make-pvar)))
            (solve-continue cont)))
        (when (unify-terms m n (length (the list (list-value l 'length))))
          (solve-continue cont)))))

(def-native-predicate take (m cont n list out)
  (let ((k (deref n)))
    (unless (typep k '(integer 0))
      (prolog-error "TAKE needs a non-negative integer count, got ~s." (lisp-argument n)))
    (let ((items (loop with l = (deref list)
                       repeat k
                       while (consp l)
                       collect (car l)
                       do (setf l (if (cut:lazy-tail-p (cdr l)) (lazy-cdr l) (deref (cdr l)))))))
      (when (unify-terms m out items) (solve-continue cont)))))

(defun term< (a b)
  "A total order on resolved terms: numbers < strings < symbols < conses < others."
  (flet ((rank (x) (typecase x (real 0) (string 1) (symbol 2) (cons 3) (t 4))))
    (let ((ra (rank a)) (rb (rank b)))
      (cond ((/= ra rb) (< ra rb))
            ((realp a) (< a b))
            ((stringp a) (and (string< a b) t))
            ((symbolp a) (let ((pa (symbol-package a)) (pb (symbol-package b)))
                           (if (and (eq pa pb) (string/= (symbol-name a) (symbol-name b)))
                               (and (string< (symbol-name a) (symbol-name b)) t)
                               (and (string< (format nil "~s" a) (format nil "~s" b)) t))))
            ((consp a) (cond ((term< (car a) (car b)) t)
                             ((term< (car b) (car a)) nil)
                             (t (term< (cdr a) (cdr b)))))
            (t nil)))))

(def-native-predicate sort (m cont list &optional predicate result)
  ;; (sort ?list ?sorted): standard order; (sort ?list ?predicate ?sorted): a Lisp predicate
  (let* ((items (copy-list (list-value list 'sort)))
         (out (if result result predicate))
         (test (if result (function-designator predicate 'sort) #'term<)))
    (when out
      (multiple-value-bind (sorted ok) (call-lisp #'stable-sort (list items test))
        (when (and ok (unify-terms m out sorted)) (solve-continue cont))))))

(def-native-predicate subset (m cont sub set)
  (let ((s (list-value set 'subset)))
    (when (every (lambda (x) (member x s :test #'equal)) (list-value sub 'subset))
      (solve-continue cont))))

(def-native-predicate reduce (m cont function list result)
  (multiple-value-bind (value ok)
      (call-lisp #'reduce (list (function-designator function 'reduce) (list-value list 'reduce)))
    (when (and ok (unify-terms m result value)) (solve-continue cont))))

(def-native-predicate max (m cont a b &optional c)
  ;; (max ?list ?max) or (max ?a ?b ?max)
  (multiple-value-bind (value ok)
      (if c
          (call-lisp #'max (list (lisp-argument a) (lisp-argument b)))
          (call-lisp #'reduce (list #'max (list-value a 'max))))
    (when (and ok (unify-terms m (or c b) value)) (solve-continue cont))))

(def-native-predicate string-concat (m cont a b &optional c)
  ;; (string-concat ?strings ?result) or (string-concat ?a ?b ?result)
  (multiple-value-bind (value ok)
      (call-lisp (lambda (&rest parts) (apply #'concatenate 'string (mapcar #'string parts)))
                 (if c (list (lisp-argument a) (lisp-argument b)) (list-value a 'string-concat)))
    (when (and ok (unify-terms m (or c b) value)) (solve-continue cont))))

;;; Calling Lisp

(def-native-predicate lisp-fun (m cont function &rest args)
  ;; the arguments but the last go to Lisp; the last is unified with the result
  (let ((lisp-args '()) (result nil) (spine (deref args)))
    (loop
      (unless (consp spine)
        (prolog-error "LISP-FUN needs a function, its arguments and a result variable: ~s."
                      (list* 'lisp-fun (lisp-argument function) (lisp-argument args))))
      (let ((rest (deref (cdr spine))))
        (when (null rest)
          (setf result (car spine))
          (return))
        (push (lisp-argument (car spine)) lisp-args)
        (setf spine rest)))
    (multiple-value-bind (value ok)
        (call-lisp (function-designator function 'lisp-fun) (nreverse lisp-args))
      (when (and ok (unify-terms m result value))
        (solve-continue cont)))))

(def-native-predicate lisp-pred (m cont function &rest args)
  (multiple-value-bind (value ok)
      (call-lisp (function-designator function 'lisp-pred) (lisp-argument args))
    (when (and ok value) (solve-continue cont))))

(def-native-predicate symbol-value (m cont symbol value)
  (let ((s (deref symbol)))
    (unless (symbolp s)
      (prolog-error "SYMBOL-VALUE needs a symbol, got ~s." (lisp-argument symbol)))
    (unless (boundp s)
      (prolog-error "SYMBOL-VALUE: the symbol ~s has no value." s))
    (when (unify-terms m value (symbol-value s)) (solve-continue cont))))

(def-native-predicate set-symbol-value (m cont symbol value)
  (let ((s (deref symbol)))
    (unless (and s (symbolp s) (not (constantp s)))
      (prolog-error "SET-SYMBOL-VALUE needs a variable's symbol, got ~s." (lisp-argument symbol)))
    (setf (symbol-value s) (lisp-argument value))
    (solve-continue cont)))

(def-native-predicate slot-value (m cont object slot value)
  ;; writes the slot when VALUE is bound, reads it otherwise
  (let ((o (lisp-argument object)) (s (deref slot)) (v (deref value)))
    (if (pvar-p v)
        (multiple-value-bind (read ok) (call-lisp #'slot-value (list o s))
          (when (and ok (unify-terms m v read)) (solve-continue cont)))
        (multiple-value-bind (written ok)
            (call-lisp (lambda (o s v) (setf (slot-value o s) v)) (list o s (lisp-argument v)))
          (declare (ignore written))
          (when ok (solve-continue cont))))))

(def-native-predicate get-slot-value (m cont object slot value)
  (multiple-value-bind (read ok) (call-lisp #'slot-value (list (lisp-argument object) (deref slot)))
    (when (and ok (unify-terms m value read)) (solve-continue cont))))

(def-native-predicate instance-of (m cont type object)
  ;; bound OBJECT: TYPE unifies with its class name; unbound: OBJECT becomes a new instance
  (let ((o (deref object)))
    (if (pvar-p o)
        (multiple-value-bind (made ok) (call-lisp #'make-instance (list (lisp-argument type)))
          (when (and ok (unify-terms m o made)) (solve-continue cont)))
        (let ((tp (deref type)))
          (if (pvar-p tp)
              (when (unify-terms m tp (class-name (class-of o))) (solve-continue cont))
              (when (typep o tp) (solve-continue cont)))))))

(def-native-predicate lisp-type (m cont object type)
  (when (unify-terms m type (type-of (lisp-argument object))) (solve-continue cont)))

;;; Output

(def-native-predicate format (m cont control &rest args)
  (multiple-value-bind (result ok)
      (call-lisp #'format (list* t (lisp-argument control) (lisp-argument args)))
    (declare (ignore result))
    (when ok (solve-continue cont))))

(def-native-predicate warn (m cont control &rest args)
  (apply #'warn (lisp-argument control) (lisp-argument args))
  (solve-continue cont))

(def-native-predicate error (m cont control &rest args)
  (apply #'error (lisp-argument control) (lisp-argument args)))
