;;;; Lazy lists: an ordinary cons chain whose last cdr is a LAZY-TAIL.
;;;; Reading past the expanded part calls the tail's generator once and splices the new cons in
;;;; place of the tail, so each element is computed once (the list is memoised) and the expanded
;;;; prefix is shared by every reader. Plain lists are lazy lists that are fully expanded.

(in-package :cram-utilities)

(defstruct (lazy-tail (:constructor %make-lazy-tail (generator)))
  "The unexpanded end of a lazy list. GENERATOR returns (values element present-p)."
  (generator nil :type function)
  (lock nil))

(defmethod print-object ((tail lazy-tail) stream)
  (print-unreadable-object (tail stream) (write-string "..." stream)))

(defun expand-tail (tail)
  "Compute the next element behind TAIL: a fresh cons (element . TAIL), or NIL at the end."
  (declare (type lazy-tail tail))
  (multiple-value-bind (element present-p) (funcall (lazy-tail-generator tail))
    (if present-p (cons element tail) nil)))

(defvar *lazy-list-dynamic-environment* nil
  "NIL, or a function of one argument (a thunk) that calls the thunk inside the dynamic
bindings of a WITH-LAZY-LIST-DYNAMIC-ENVIRONMENT form. A lazy list made while it is set computes
every element inside those bindings.")

(defun make-lazy-list (generator)
  "Return a lazy list whose elements are produced by calling GENERATOR, a function of no
arguments returning (values element present-p); PRESENT-P NIL ends the list. The first element
is computed at once (an empty generator gives NIL). Inside WITH-LAZY-LIST-DYNAMIC-ENVIRONMENT
every element is computed with that form's special bindings."
  (check-type generator function)
  (let ((environment *lazy-list-dynamic-environment*))
    (expand-tail (%make-lazy-tail
                  (if environment
                      (lambda () (funcall (the function environment) generator))
                      generator)))))

(defmacro with-lazy-list-dynamic-environment ((&rest bindings) &body body)
  "Evaluate BODY so that every lazy list it creates computes its elements, whenever they are
read, with the special variables of BINDINGS ((variable value-form) ...) bound to the values
the VALUE-FORMs have now."
  (let ((names (mapcar (lambda (b) (if (consp b) (first b) b)) bindings))
        (values (gensym "VALUES")) (outer (gensym "OUTER")) (thunk (gensym "THUNK")))
    (dolist (name names)
      (unless (and (symbolp name) name (not (constantp name)))
        (error "WITH-LAZY-LIST-DYNAMIC-ENVIRONMENT: ~s is not a variable name." name)))
    `(let ((,values (list ,@(mapcar (lambda (b) (if (consp b) (second b) nil)) bindings)))
           (,outer *lazy-list-dynamic-environment*))
       (let ((*lazy-list-dynamic-environment*
               (lambda (,thunk)
                 (flet ((inside () (progv ',names ,values (funcall ,thunk))))
                   (if ,outer (funcall ,outer #'inside) (inside))))))
         ,@body))))

;;; Delayed values

(defstruct (delay (:constructor %make-delay (generator)) (:copier nil) (:predicate delay-p))
  "A value computed on first FORCE and remembered."
  (generator nil :type (or null function))
  (value nil))

(setf (documentation 'delay-p 'function) "True when OBJECT is a delayed value made by DELAY.")

(defmacro delay (&body body)
  "A delayed value: BODY is evaluated the first time the value is FORCEd, and only then."
  `(%make-delay (lambda () ,@body)))

(defun force (object)
  "The value of the delayed value OBJECT, computing it on the first call; any other object is
its own value."
  (if (delay-p object)
      (let ((generator (delay-generator object)))
        (when generator
          (setf (delay-value object) (funcall generator)
                (delay-generator object) nil))
        (delay-value object))
      object))

(defmacro lazy-list ((&rest bindings) &body body)
  "Build a lazy list from a generator loop. BINDINGS are (var init) pairs holding the loop state.
BODY is evaluated for each step and must end the step with one of the local forms:
  (CONT value new-values...) yield VALUE, then continue with the state set to NEW-VALUES;
  (NEXT new-values...)       yield nothing, continue with the new state;
  (FINISH [value])           end the list, yielding VALUE first when given.
New values are assigned to the BINDINGS variables in order; missing ones keep their value.
A step whose BODY returns without one of them ends the list (as (FINISH))."
  (let ((vars (mapcar (lambda (b) (if (consp b) (first b) b)) bindings))
        (step (gensym "STEP")) (done (gensym "DONE")) (result (gensym "RESULT")))
    `(let (,@(mapcar (lambda (b) (if (consp b) (list (first b) (second b)) (list b nil))) bindings)
           (,done nil))
       (make-lazy-list
        (lambda ()
          (if ,done
              (values nil nil)
              (block ,result
                (loop
                  (block ,step
                    (macrolet ((cont (value &rest new-values)
                                 `(let ((v ,value))
                                    (psetq ,@(mapcan #'list (subseq ',vars 0 (length new-values))
                                                     new-values))
                                    (return-from ,',result (values v t))))
                               (next (&rest new-values)
                                 `(progn (psetq ,@(mapcan #'list
                                                          (subseq ',vars 0 (length new-values))
                                                          new-values))
                                         (return-from ,',step)))
                               (finish (&optional (value nil value-p))
                                 `(progn (setf ,',done t)
                                         (return-from ,',result
                                           ,(if value-p `(values ,value t) '(values nil nil))))))
                      ,@body
                      (setf ,done t)
                      (return-from ,result (values nil nil))))))))))))

(declaim (inline lazy-list-p))
(defun lazy-list-p (object)
  "True when OBJECT is a list or a lazy list (a cons chain that may end in a lazy tail)."
  (listp object))

(defun not-a-list-error (function object)
  (error 'lazy-list-type-error :function function :datum object))

(define-condition lazy-list-type-error (simple-error)
  ((function :initarg :function :reader lazy-list-type-error-function)
   (datum :initarg :datum :reader lazy-list-type-error-datum))
  (:default-initargs :format-control "Expected a list or a lazy list." :format-arguments '())
  (:documentation "A lazy-list function was given something that is neither a list nor a lazy
list (a SIMPLE-ERROR, as CRAM's LAZY-MAPCAN signals).")
  (:report (lambda (c s)
             (let ((*print-length* 10) (*print-level* 4))
               (format s "~s: expected a list or a lazy list, got ~s."
                       (lazy-list-type-error-function c) (lazy-list-type-error-datum c))))))

(defun lazy-car (list)
  "The first element of the lazy LIST."
  (if (listp list)
      (car list)
      (not-a-list-error 'lazy-car list)))

(defun lazy-cdr (list)
  "The rest of the lazy LIST, computing its next element if needed (at most once)."
  (unless (listp list)
    (not-a-list-error 'lazy-cdr list))
  (let ((rest (cdr list)))
    (if (lazy-tail-p rest)
        (setf (cdr list) (expand-tail rest))
        rest)))

(defmacro lazy-dolist ((var list &optional result) &body body)
  "Like DOLIST over a lazy list, expanding it one element at a time."
  (let ((l (gensym "L")))
    `(do ((,l ,list (lazy-cdr ,l)))
         ((null ,l) ,result)
       (let ((,var (car ,l)))
         ,@body))))

(defun force-ll (list)
  "Expand every element of the lazy LIST and return it as an ordinary list. Never returns for an
infinite lazy list."
  (unless (listp list)
    (not-a-list-error 'force-ll list))
  (do ((l list (lazy-cdr l)))
      ((not (consp l))
       (if (null l) list (not-a-list-error 'force-ll list)))))

(defun expanded-length (list)
  "The number of elements of the lazy LIST computed so far (no further expansion)."
  (loop for l = list then (cdr l) while (consp l) count t))

(defun lazy-mapcar (function &rest lists)
  "Lazily map FUNCTION over the elements of LISTS in parallel; ends with the shortest list."
  (let ((ls lists) (started nil))
    (make-lazy-list
     (lambda ()
       ;; advance only when the next element is asked for
       (if started (setf ls (mapcar #'lazy-cdr ls)) (setf started t))
       (if (some #'null ls)
           (values nil nil)
           (values (apply function (mapcar #'car ls)) t))))))

(defun lazy-mapcan (function list &rest more-lists)
  "Lazily append the (lazy) lists that FUNCTION returns for the elements of LIST and
MORE-LISTS taken in parallel (ending with the shortest). A result that is not a list signals
LAZY-LIST-TYPE-ERROR (a SIMPLE-ERROR, as in CRAM) when the list reaches it."
  (let ((outers (cons list more-lists)) (inner nil) (started nil))
    (make-lazy-list
     (lambda ()
       (loop
         (cond (inner
                (let ((element (car inner)))
                  (setf inner (lazy-cdr inner))
                  (return (values element t))))
               ((and started (some #'null outers)) (return (values nil nil)))
               (t
                (if started (setf outers (mapcar #'lazy-cdr outers)) (setf started t))
                (when (some #'null outers) (return (values nil nil)))
                (let ((result (apply function (mapcar #'car outers))))
                  (unless (listp result)
                    (not-a-list-error 'lazy-mapcan result))
                  (setf inner result)))))))))

(defun lazy-filter (predicate list)
  "The lazy list of the elements of LIST for which PREDICATE is true."
  (let ((l list) (started nil))
    (make-lazy-list
     (lambda ()
       (loop
         (if started (setf l (lazy-cdr l)) (setf started t))
         (when (null l) (return (values nil nil)))
         (when (funcall predicate (car l)) (return (values (car l) t))))))))

(defun lazy-append (&rest lists)
  "The lazy concatenation of the (lazy) LISTS; later lists are not touched until reached."
  (lazy-mapcan #'identity lists))

(defun lazy-take (n list)
  "A lazy list of the first N elements of the (possibly infinite) lazy LIST."
  (check-type n (integer 0))
  (let ((l list) (left n) (started nil))
    (make-lazy-list
     (lambda ()
      (block lazy-take-step
       (when (<= left 0) (return-from lazy-take-step (values nil nil)))
       (if started (setf l (lazy-cdr l)) (setf started t))
       (if (null l)
           (values nil nil)
           (progn (decf left) (values (car l) t))))))))

(defun lazy-elt (list n)
  "The N-th element (0-based) of the lazy LIST, or NIL when it is shorter."
  (check-type n (integer 0))
  (loop repeat n
        while list
        do (setf list (lazy-cdr list)))
  (car list))

(defun lazy-fold (function list &key (initial-value nil initial-p))
  "Fold FUNCTION (accumulator element) over the lazy LIST from the left. Without INITIAL-VALUE
the first element starts the accumulator."
  (let ((acc initial-value) (l list))
    (unless initial-p
      (setf acc (car l) l (lazy-cdr l)))
    (lazy-dolist (element l acc)
      (setf acc (funcall function acc element)))))

(defun lazy-skip (n list)
  "The lazy LIST without its first N elements (NIL when it is shorter)."
  (check-type n (integer 0))
  (loop repeat n while list do (setf list (lazy-cdr list)))
  list)

(defun lazy-flatten (list)
  "A lazy list of the atoms of the (lazy) tree LIST, depth first."
  (lazy-mapcan (lambda (element)
                 (if (listp element) (lazy-flatten element) (list element)))
               list))

(defun lazy-rests (list)
  "The lazy list of LIST and each of its successive lazy tails."
  (let ((l list) (started nil))
    (make-lazy-list
     (lambda ()
       (if started (setf l (lazy-cdr l)) (setf started t))
       (if l (values l t) (values nil nil))))))
