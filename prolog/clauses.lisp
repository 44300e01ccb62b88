;;;; Running compiled clauses: a predicate's entry function selects, by the first argument of
;;;; the call, the clauses that can match, and tries them in turn under a choice point.

(in-package :cram-prolog)

(declaim (optimize (speed 3) (safety 1) (debug 0)))

;;; Running clauses
;;;
;;; A predicate's entry selects, from the dereferenced first argument of the call, the list of
;;; clauses that can match it (all of them when it is unbound; the clauses with a variable or a
;;; compound first argument for a compound; for an atom the clauses with that key or a variable
;;; first argument, in their order). Every clause of a selected list is then tried in turn, with
;;; no further filtering.

(declaim (inline first-arg-of))
(defun first-arg-of (args)
  "The dereferenced first argument of the run-time argument list ARGS, or +UNBOUND+ when unknown."
  (let ((args (deref args)))
    (if (consp args)
        (let ((a (deref (car args))))
          (if (pvar-p a) +unbound+ a))
        +unbound+)))

(sb-ext:defglobal +empty-frame+ (vector)
  "The frame of a clause without variables.")

(defun grow-scratch (m n)
  (declare (type machine m) (type fixnum n))
  (setf (machine-scratch m) (make-array (max n (* 2 (length (machine-scratch m)))))))

(declaim (inline match-head))
(defun match-head (m clause args)
  "Match CLAUSE's head with ARGS; the frame holding the head's variables, or NIL on failure. A
clause with variables is matched in M's scratch frame."
  (declare (type clause clause) (type machine m))
  (let ((n (clause-nvars clause)))
    (declare (type fixnum n))
    (if (zerop n)
        (and (funcall (clause-match clause) m +empty-frame+ args) +empty-frame+)
        (let ((scratch (machine-scratch m)))
          (when (< (length scratch) n)
            (setf scratch (grow-scratch m n)))
          (and (funcall (clause-match clause) m scratch args) scratch)))))

(declaim (inline enter-body))
(defun enter-body (m clause head-frame cont barrier)
  "Run the body of CLAUSE (or CONT for a fact) after its head matched into HEAD-FRAME."
  (declare (type clause clause) (type simple-vector head-frame))
  (let ((body (clause-body clause))
        (n (clause-nvars clause)))
    (declare (type fixnum n))
    (cond ((null body) (funcall (the function cont)))
          ((zerop n) (funcall (the function body) m +empty-frame+ cont barrier))
          ((clause-frameless clause)
           ;; the single goal builds its arguments from the head frame before anything else
           ;; uses it, so the scratch frame serves
           (loop for (i . name) in (clause-init clause)
                 do (setf (svref head-frame i) (make-pvar name)))
           (funcall (the function body) m head-frame cont barrier))
          (t (let ((frame (make-array n)))
               (dotimes (i (clause-nhead clause))
                 (setf (svref frame i) (svref head-frame i)))
               (loop for (i . name) in (clause-init clause)
                     do (setf (svref frame i) (make-pvar name)))
               (funcall (the function body) m frame cont barrier))))))

(declaim (inline run-clause))
(defun run-clause (m clause args cont barrier)
  "Match CLAUSE's head with ARGS, then run its body (or CONT for a fact)."
  (let ((frame (match-head m clause args)))
    (when frame
      (enter-body m clause frame cont barrier))))

(defun resume-clauses (m index clauses)
  "Try CLAUSES in turn under the choice point at INDEX (the newest), which holds the call's
arguments and continuation: a clause whose head does not match is skipped at once; the choice
point is dropped before the last clause."
  (declare (type machine m) (type fixnum index) (optimize (safety 0)))
  (let ((args (cp-data m index 1))
        (cont (cp-data m index 2)))
    (loop
      (let ((clause (car clauses))
            (rest (cdr clauses)))
        (when (null rest)
          (setf (machine-cp-top m) index)
          (return (run-clause m clause args cont index)))
        (setf (cp-data m index 0) rest)
        (let ((frame (match-head m clause args)))
          (when frame
            (return (enter-body m clause frame cont index)))
          (undo-trail m (svref (machine-cps m) index))
          (setf clauses rest))))))

(defun retry-clauses (m index)
  "Choice point of TRY-CLAUSES: try the clauses left in data slot 0."
  (resume-clauses m index (cp-data m index 0)))

(declaim (inline try-clauses))
(defun try-clauses (m clauses args cont)
  "Run each of the CLAUSES (a non-empty list) in turn, leaving a choice point for the rest."
  (count-step m)
  (if (cdr clauses)
      (resume-clauses m (push-cp m #'retry-clauses clauses args cont) clauses)
      (run-clause m (car clauses) args cont (machine-cp-top m))))

(declaim (inline eq-key-p))
(defun eq-key-p (x)
  "True for the atoms that EQUAL compares like EQ."
  (typep x '(or symbol fixnum character)))

(declaim (inline eq-key-hash))
(defun eq-key-hash (x)
  (declare (type (or symbol fixnum character) x))
  (typecase x
    (symbol (sxhash x))
    (fixnum (logand x most-positive-fixnum))
    (t (char-code x))))

(defun make-key-lookup (keys buckets default)
  "A function of a run-time atom returning the bucket of the key EQUAL to it, or DEFAULT. KEYS
and BUCKETS are parallel lists, the keys distinct under EQUAL."
  (let ((n (length keys)))
    (cond ((zerop n) (lambda (a) (declare (ignore a)) default))
          ((and (every #'eq-key-p keys) (<= n 6))
           (let ((kv (coerce keys 'simple-vector))
                 (bv (coerce buckets 'simple-vector)))
             (lambda (a)
               (dotimes (i n default)
                 (when (eq (svref kv i) a) (return (svref bv i)))))))
          ((every #'eq-key-p keys)
           ;; open addressing over a power-of-two table at most half full
           (let* ((size (ash 1 (integer-length (* 2 n))))
                  (mask (1- size))
                  (empty (make-symbol "EMPTY"))
                  (kv (make-array size :initial-element empty))
                  (bv (make-array size :initial-element default)))
             (declare (type fixnum mask))
             (loop for k in keys
                   for b in buckets
                   do (let ((i (logand (eq-key-hash k) mask)))
                        (declare (type fixnum i))
                        (loop until (eq (svref kv i) empty)
                              do (setf i (logand (1+ i) mask)))
                        (setf (svref kv i) k (svref bv i) b)))
             (lambda (a)
               (if (eq-key-p a)
                   (let ((i (logand (the fixnum (eq-key-hash a)) mask)))
                     (declare (type fixnum i))
                     (loop
                       (let ((k (svref kv i)))
                         (cond ((eq k a) (return (svref bv i)))
                               ((eq k empty) (return default)))
                         (setf i (logand (1+ i) mask)))))
                   default))))
          (t (let ((table (make-hash-table :test 'equal :size n)))
               (loop for k in keys
                     for b in buckets
                     do (setf (gethash k table) b))
               (lambda (a) (values (gethash a table default))))))))

(defun clause-selection (clauses)
  "How an entry selects among CLAUSES by the first argument of a call: NIL when every clause
has a variable first argument and none has a first-goal guard (all are tried); else the
function of a run-time atom or object returning its clauses (those with that key or a variable
first argument, in order; for an object, the guarded ones only when GUARD-SELECTION keeps
them) and, second value, the clauses for a compound first argument."
  (let* ((var-clauses (remove-if-not (lambda (c) (= 0 (clause-kind c))) clauses))
         (guarded (guard-selection var-clauses)))
    (if (= (length var-clauses) (length clauses))
        (and guarded (values guarded clauses))
        (let ((cons-clauses (remove 1 clauses :key #'clause-kind))
              (table (make-hash-table :test 'equal)) (keys '()) (vars-so-far '()))
          ;; bucket per atom key: the clauses with that key or a variable first argument
          (dolist (c clauses)
            (case (clause-kind c)
              (0 (push c vars-so-far)
               (maphash (lambda (k bucket) (setf (gethash k table) (cons c bucket))) table))
              (1 (let ((bucket (gethash (clause-key c) table :none)))
                   (when (eq bucket :none)
                     (push (clause-key c) keys))
                   (setf (gethash (clause-key c) table)
                         (cons c (if (eq bucket :none) vars-so-far bucket)))))))
          (setf keys (nreverse keys))
          (let ((lookup (make-key-lookup keys (mapcar (lambda (k) (reverse (gethash k table))) keys)
                                         var-clauses)))
            (values (if guarded
                        (lambda (a)
                          (let ((selected (funcall (the function lookup) a)))
                            ;; an object no clause names: its variable clauses, by their guards
                            (if (eq selected var-clauses) (funcall (the function guarded) a) selected)))
                        lookup)
                    cons-clauses))))))

(defun make-clauses-entry (clauses)
  "The entry function running CLAUSES, selecting them by the first argument of the call."
  (multiple-value-bind (lookup cons-clauses) (clause-selection clauses)
    (if (null lookup)
        (lambda (m args cont)
          (declare (optimize (safety 0)))
          (try-clauses m clauses args cont))
        (lambda (m args cont)
          (declare (optimize (safety 0)))
          (let* ((a (first-arg-of args))
                 (selected (cond ((eq a +unbound+) clauses)
                                 ((consp a) cons-clauses)
                                 (t (funcall (the function lookup) a)))))
            (when selected
              (try-clauses m selected args cont)))))))

;;; Calls with their arguments passed one by one (1 to 4 of them): no argument list is made
;;; unless a choice point must keep the arguments.

(defmacro positional-match-head (m clause &rest as)
  "Like MATCH-HEAD for the arguments AS passed one by one."
  `(let ((n (clause-nvars ,clause)))
     (declare (type fixnum n))
     (if (zerop n)
         (and (funcall (the function (clause-match-n ,clause)) ,m +empty-frame+ ,@as)
              +empty-frame+)
         (let ((scratch (machine-scratch ,m)))
           (when (< (length scratch) n)
             (setf scratch (grow-scratch ,m n)))
           (and (funcall (the function (clause-match-n ,clause)) ,m scratch ,@as) scratch)))))

(defmacro define-positional-resume (n)
  "RESUME-CLAUSES-N and RETRY-CLAUSES-N: RESUME-CLAUSES and RETRY-CLAUSES for clauses of N
arguments, under a choice point whose data slots 1, 3, 4 and 5 hold the call's arguments."
  (let ((resume (intern (format nil "RESUME-CLAUSES-~d" n)))
        (retry (intern (format nil "RETRY-CLAUSES-~d" n)))
        (as (loop for i from 1 to n collect (gensym "A"))))
    `(progn
       (defun ,resume (m index clauses)
         (declare (type machine m) (type fixnum index) (optimize (safety 0)))
         (let (,@(loop for a in as for slot in '(1 3 4 5)
                       collect `(,a (cp-data m index ,slot)))
               (cont (cp-data m index 2)))
           (loop
             (let ((clause (car clauses))
                   (rest (cdr clauses)))
               (declare (type clause clause))
               (when (null rest)
                 (setf (machine-cp-top m) index)
                 (let ((frame (positional-match-head m clause ,@as)))
                   (return (and frame (enter-body m clause frame cont index)))))
               (setf (cp-data m index 0) rest)
               (let ((frame (positional-match-head m clause ,@as)))
                 (when frame
                   (return (enter-body m clause frame cont index)))
                 (undo-trail m (svref (machine-cps m) index))
                 (setf clauses rest))))))
       (defun ,retry (m index)
         (,resume m index (cp-data m index 0))))))

(define-positional-resume 1)
(define-positional-resume 2)
(define-positional-resume 3)
(define-positional-resume 4)

(defmacro run-selected-positional (m selected cont &rest as)
  "Try the clauses SELECTED (a list; NIL fails) on the arguments AS, like TRY-CLAUSES."
  (let ((resume (intern (format nil "RESUME-CLAUSES-~d" (length as))))
        (retry (intern (format nil "RETRY-CLAUSES-~d" (length as)))))
    `(let ((selected ,selected))
       (when selected
         (count-step ,m)
         (if (cdr selected)
             (,resume ,m (push-cp ,m #',retry selected ,(first as) ,cont ,@(rest as)) selected)
             (let* ((clause (car selected))
                    (frame (positional-match-head ,m clause ,@as)))
               (declare (type clause clause))
               (when frame
                 (enter-body ,m clause frame ,cont (machine-cp-top ,m)))))))))

(defmacro positional-clauses-entry (n clauses lookup cons-clauses)
  "The entry (M A1 ... AN CONT) of CLAUSES selected as LOOKUP and CONS-CLAUSES say (see
CLAUSE-SELECTION)."
  (let ((as (loop for i from 1 to n collect (gensym "A"))))
    `(if (null ,lookup)
         (lambda (m ,@as cont)
           (declare (type machine m) (optimize (safety 0)))
           (run-selected-positional m ,clauses cont ,@as))
         (lambda (m ,@as cont)
           (declare (type machine m) (optimize (safety 0)))
           (let ((a (deref ,(first as))))
             (run-selected-positional m (cond ((pvar-p a) ,clauses)
                                              ((consp a) ,cons-clauses)
                                              (t (funcall (the function ,lookup) a)))
                                      cont ,@as))))))

(defun make-positional-clauses-entry (clauses n)
  "The entry (M A1 ... AN CONT) for calls of N (1 to 4) arguments passed one by one, running
those of CLAUSES with N head arguments; NIL when one of CLAUSES has an argument list that is
not a proper list (it is matched against the call's argument list)."
  (unless (some (lambda (c) (minusp (clause-arity c))) clauses)
    (let ((clauses (remove n clauses :key #'clause-arity :test #'/=)))
      (if (null clauses)
          (lambda (&rest args) (declare (ignore args)) nil)
          (multiple-value-bind (lookup cons-clauses) (clause-selection clauses)
            (ecase n
              (1 (positional-clauses-entry 1 clauses lookup cons-clauses))
              (2 (positional-clauses-entry 2 clauses lookup cons-clauses))
              (3 (positional-clauses-entry 3 clauses lookup cons-clauses))
              (4 (positional-clauses-entry 4 clauses lookup cons-clauses))))))))
