;;;; Run-time terms: logic variables bound destructively, the trail, choice points, unification.
;;;;
;;;; A run-time term is an s-expression whose variables are PVAR structures. A query's ?symbols
;;;; become PVARs when the query starts; clause variables become PVARs (or are shared with the
;;;; caller's terms) when a clause is entered. Bindings are undone on backtracking through the
;;;; trail. The choice-point stack holds, per choice point, the trail height and a resume function
;;;; with its data, so a solver can stop after a solution and be resumed later.

(in-package :cram-prolog)

(declaim (optimize (speed 3) (safety 1) (debug 0)))

(defconstant +unbound+ '+unbound+
  "The value slot of an unbound PVAR.")

(declaim (inline %make-pvar))
(defstruct (pvar (:constructor %make-pvar ())
                 (:copier nil))
  "A logic variable. VALUE is +UNBOUND+ or the term it is bound to."
  (value +unbound+))

(declaim (inline make-pvar))
(defun make-pvar (&optional name)
  "A fresh unbound variable (NAME, the source ?symbol, is not stored)."
  (declare (ignore name))
  (%make-pvar))

(defmethod print-object ((v pvar) stream)
  (if (eq (pvar-value v) +unbound+)
      (format stream "#<?_ ~x>" (sb-kernel:get-lisp-obj-address v))
      (format stream "#<?=~s>" (pvar-value v))))

(declaim (inline deref))
(defun deref (term)
  "TERM with leading bound variables followed to their values."
  (loop while (and (pvar-p term) (not (eq (pvar-value term) +unbound+)))
        do (setf term (pvar-value term)))
  term)

(defconstant +cp-size+ 8
  "Slots per choice point: trail height, resume function, six data slots (three of them used by
the clause choice points of calls with up to four arguments passed one by one).")

(defstruct (machine (:constructor %make-machine))
  "The state of one running query: trail and choice-point stack."
  (trail #() :type simple-vector)
  (trail-top 0 :type fixnum)
  (cps #() :type simple-vector)
  (cp-top 0 :type fixnum)
  ;; predicate calls made so far; every +RESOURCE-CHECK-INTERVAL+ calls the heap is checked
  (steps 0 :type fixnum)
  ;; frame into which clause heads are matched before a clause's own frame is allocated
  (scratch #() :type simple-vector))

(defun make-machine ()
  "A fresh machine with empty trail and choice-point stack."
  (%make-machine :scratch (make-array 8)))

(defun grow-vector (vector)
  (declare (type simple-vector vector))
  (let ((new (make-array (max 24 (* 2 (length vector))))))
    (replace new vector)
    new))

;;; Resource limits. A runaway recursion keeps the continuations, frames and choice points of
;;; every level alive, so it fills the heap (SBCL dies with "Heap exhausted, game over" when a
;;; garbage collection finds no room to copy into); a deep term overflows the Lisp stack. The
;;; heap is checked every +RESOURCE-CHECK-INTERVAL+ predicate calls of a query; the stack is
;;; guarded by the guard page (PROLOG turns the STORAGE-CONDITION into PROLOG-RESOURCE-ERROR).

;;; The heap is checked every +RESOURCE-CHECK-INTERVAL+ predicate calls and before every
;;; solution is returned (a solution may copy a large term).

(defconstant +resource-check-interval+ 64
  "Predicate calls between two checks of the heap during a query (a power of two).")

(defvar *prolog-heap-limit* :default
  "The most bytes of dynamic space (the Lisp heap, every thread's data together) that may be in
use while a Prolog query runs, NIL for no limit, or :DEFAULT for a third of the dynamic space of
the running process (taken when a query checks, so a saved core started with a larger
--dynamic-space-size gets a larger limit). When a query finds more in use, it collects
garbage; when that does not bring the use under the limit, the query signals
PROLOG-RESOURCE-ERROR and unwinds, and the memory it held is collected. The default is a third
of the dynamic space (SBCL's --dynamic-space-size): a collection needs free room to copy the
surviving data into, and with half of the space in use SBCL already died in a collection
\(measured). Measured with a 1 GB dynamic space: (grow ?x) :- (grow (s ?x)), (true) and the
left recursion (anc ?x ?y) :- (anc ?x ?z), (par ?z ?y) are stopped after about 2.5 million
levels (about 100 bytes per level) in 2-3 s; before, both killed SBCL.")

(defun signal-resource-error (format &rest args)
  "Signal PROLOG-RESOURCE-ERROR with the formatted message."
  (error 'prolog-resource-error :message (apply #'format nil format args)))

(declaim (inline heap-in-use))
(defun heap-in-use ()
  (sb-kernel:dynamic-usage))

(defun check-resources-slowly (m limit)
  (declare (type machine m))
  (sb-ext:gc :full t)
  (let ((used (heap-in-use)))
    (when (> used limit)
      (signal-resource-error
       "The Prolog query used more heap than PROLOG:*PROLOG-HEAP-LIMIT* allows (~:d bytes in ~
use of ~:d allowed) after ~:d predicate calls: probably an endless recursion (a predicate ~
calling itself with an ever growing term, a left recursion such as (anc ?x ?y) :- (anc ?x ?z) ~
..., or endlessly many solutions read with FORCE-LL). The query was abandoned; the image is ~
unharmed."
       used limit (machine-steps m)))))

(declaim (inline check-resources))
(defun heap-limit ()
  "The byte limit *PROLOG-HEAP-LIMIT* stands for, or NIL. Another value is an error naming it."
  (let ((limit *prolog-heap-limit*))
    (cond ((null limit) nil)
          ((eq limit :default) (floor (sb-ext:dynamic-space-size) 3))
          ((typep limit '(integer 1)) limit)
          (t (error 'prolog-error
                    :message (format nil "PROLOG:*PROLOG-HEAP-LIMIT* is ~s, expected a positive ~
                                          number of bytes, NIL or :DEFAULT." limit))))))

(defun check-resources (m)
  "Signal PROLOG-RESOURCE-ERROR when the heap in use exceeds *PROLOG-HEAP-LIMIT* even after a
garbage collection."
  (let ((limit (heap-limit)))
    (when (and limit (> (heap-in-use) (the fixnum limit)))
      (check-resources-slowly m limit))))

(declaim (inline count-step))
(defun count-step (m)
  "Count one predicate call of M's query; check the resources every +RESOURCE-CHECK-INTERVAL+."
  (declare (type machine m))
  (let ((n (logand (1+ (machine-steps m)) most-positive-fixnum)))
    (declare (type fixnum n))
    (setf (machine-steps m) n)
    (when (zerop (logand n (1- +resource-check-interval+)))
      (check-resources m))))

(sb-ext:defglobal **spare-machine** nil
  "A machine left by a finished query, ready for the next one.")

(defconstant +max-pooled-size+ 256
  "Machines whose stacks grew beyond this many slots are not kept for reuse.")

(defun acquire-machine ()
  "An idle machine with empty stacks: the spare one when there is one, else a fresh one."
  (let ((m **spare-machine**))
    (if (and m (eq (sb-ext:compare-and-swap (symbol-value '**spare-machine**) m nil) m))
        m
        (make-machine))))

(defun release-machine (m)
  "Offer the machine M of a finished query (no choice point, nothing trailed) for reuse."
  (declare (type machine m))
  (when (and (zerop (machine-cp-top m)) (zerop (machine-trail-top m))
             (<= (length (machine-cps m)) +max-pooled-size+)
             (<= (length (machine-trail m)) +max-pooled-size+)
             (<= (length (machine-scratch m)) +max-pooled-size+))
    ;; drop references to the finished query's terms and continuations
    (fill (machine-cps m) 0)
    (fill (machine-scratch m) 0)
    (setf **spare-machine** m))
  nil)

(declaim (inline bind-var))
(defun bind-var (m var value)
  "Bind the unbound VAR to VALUE, recording it on M's trail when a choice point could undo it."
  (declare (type machine m) (type pvar var))
  (setf (pvar-value var) value)
  (unless (zerop (machine-cp-top m))
    (let ((top (machine-trail-top m))
          (trail (machine-trail m)))
      (when (>= top (length trail))
        (setf trail (grow-vector trail)
              (machine-trail m) trail))
      (setf (svref trail top) var
            (machine-trail-top m) (1+ top))))
  t)

(declaim (inline undo-trail))
(defun undo-trail (m mark)
  "Unbind every variable trailed after MARK."
  (declare (type machine m) (type fixnum mark))
  (let ((trail (machine-trail m)))
    (loop for i of-type fixnum from (1- (machine-trail-top m)) downto mark
          do (setf (pvar-value (the pvar (svref trail i))) +unbound+))
    (setf (machine-trail-top m) mark)))

(declaim (inline push-cp))
(defun push-cp (m function a b c &optional (d nil d-p) (e nil e-p) (f nil f-p))
  "Push a choice point resuming with (FUNCTION M INDEX) where data slots 0 to 2 hold A B C, and
slots 3 to 5 D E F when given."
  (declare (type machine m))
  (let ((top (machine-cp-top m))
        (cps (machine-cps m)))
    (declare (type fixnum top))
    (when (> (+ top +cp-size+) (length cps))
      (setf cps (grow-vector cps)
            (machine-cps m) cps))
    (setf (svref cps top) (machine-trail-top m)
          (svref cps (+ top 1)) function
          (svref cps (+ top 2)) a
          (svref cps (+ top 3)) b
          (svref cps (+ top 4)) c
          (machine-cp-top m) (+ top +cp-size+))
    (when d-p (setf (svref cps (+ top 5)) d))
    (when e-p (setf (svref cps (+ top 6)) e))
    (when f-p (setf (svref cps (+ top 7)) f))
    top))

(declaim (inline cut-to))
(defun cut-to (m height)
  "Remove every choice point above HEIGHT."
  (declare (type machine m) (type fixnum height))
  (when (< height (machine-cp-top m))
    (setf (machine-cp-top m) height)
    (when (zerop height)
      ;; nothing is left to undo: bindings are final
      (let ((trail (machine-trail m)))
        (fill trail 0 :end (machine-trail-top m))
        (setf (machine-trail-top m) 0))))
  nil)

(defun backtrack (m)
  "Resume the newest choice point until one reports a solution (T); NIL when none is left."
  (declare (type machine m))
  (loop
    (let ((top (machine-cp-top m)))
      (declare (type fixnum top))
      (when (zerop top) (return nil))
      (let* ((index (- top +cp-size+))
             (cps (machine-cps m)))
        (undo-trail m (svref cps index))
        (when (funcall (the function (svref cps (+ index 1))) m index)
          (return t))))))

(declaim (inline cp-data))
(defun cp-data (m index slot)
  (svref (machine-cps m) (+ (the fixnum index) 2 (the fixnum slot))))

(declaim (inline (setf cp-data)))
(defun (setf cp-data) (value m index slot)
  (setf (svref (machine-cps m) (+ (the fixnum index) 2 (the fixnum slot))) value))

(defun unify-terms (m a b)
  "Unify the run-time terms A and B on machine M; true on success. Atoms unify when EQUAL."
  (declare (type machine m))
  (loop
    (setf a (deref a) b (deref b))
    (cond ((eq a b) (return t))
          ((pvar-p a) (return (bind-var m a b)))
          ((pvar-p b) (return (bind-var m b a)))
          ((consp a)
           (unless (and (consp b) (unify-terms m (car a) (car b)))
             (return nil))
           (setf a (cdr a) b (cdr b)))
          ;; symbols, fixnums and characters are EQUAL only when EQ
          ((or (typep a '(or symbol fixnum character)) (typep b '(or symbol fixnum character)))
           (return nil))
          (t (return (equal a b))))))

(defun resolve-term (term &optional map)
  "TERM with every bound variable replaced by its value, recursively. Unbound variables stay,
or are replaced through MAP (a function of the variable) when given. Shares unchanged parts."
  (let ((term (deref term)))
    (cond ((pvar-p term) (if map (funcall (the function map) term) term))
          ((consp term) (resolve-list term map))
          (t term))))

(defun resolve-list (list map)
  "RESOLVE-TERM of the cons LIST, walking its spine iteratively."
  (let ((items '()) (x list) (changed nil) (tail nil))
    (loop
      (let ((a (resolve-term (car x) map)))
        (push a items)
        (unless (eq a (car x)) (setf changed t)))
      (let* ((d (cdr x)) (dd (deref d)))
        (unless (eq d dd) (setf changed t))
        (if (consp dd)
            (setf x dd)
            (progn
              (setf tail (if (pvar-p dd) (if map (funcall (the function map) dd) dd) dd))
              (unless (eq tail d) (setf changed t))
              (return)))))
    (if changed
        (let ((result tail))
          (dolist (a items result) (setf result (cons a result))))
        list)))

(defun deref-term (term)
  "TERM with its leading bound variables followed (not substituted inside)."
  (deref term))

(defun term-ground-p (term)
  "True when TERM contains no unbound variable."
  (let ((term (deref term)))
    (loop
      (cond ((pvar-p term) (return nil))
            ((consp term)
             (unless (term-ground-p (car term)) (return nil))
             (setf term (deref (cdr term))))
            (t (return t))))))

(defun copy-term-fresh (term)
  "TERM resolved, with its unbound variables replaced by fresh ones (consistently)."
  (when (term-ground-p term)
    (return-from copy-term-fresh (resolve-term term)))
  (let ((map '()))
    (resolve-term term (lambda (v)
                         (or (cdr (assoc v map :test #'eq))
                             (let ((new (make-pvar)))
                               (push (cons v new) map)
                               new))))))
