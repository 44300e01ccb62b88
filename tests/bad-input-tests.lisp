;;;; The bad-input suite: table-driven cases of what a user may type at every layer (Prolog,
;;;; plan language, transforms, designators here; belief state, URDF, simulated robot and
;;;; costmaps in bad-input-projection-tests.lisp). Each case states the outcome it must have:
;;;;
;;;;   :error    a clear error: a condition whose message contains the value as the user wrote
;;;;             it (MATCH), that is not a raw SBCL condition (TYPE-ERROR, CONTROL-ERROR,
;;;;             FLOATING-POINT-*, STORAGE-CONDITION, UNDEFINED-FUNCTION ...), and whose message
;;;;             names no internal handle;
;;;;   :fails    a documented Prolog failure (the query returns NIL);
;;;;   :accepts  valid (if unusual) input that must work;
;;;;   :warns    input that is corrected with a warning (as CRAM does).
;;;;
;;;; Anything else is VAGUE (a raw condition, an unexpected value, silence) or a CRASH (stack or
;;;; heap exhausted, a timeout). The suite prints its counts.

(defpackage :cram-plans-tests.bad-input
  (:use :cl :fiveam)
  (:import-from :cram-prolog #:prolog #:<- #:def-fact-group)
  (:import-from :cram-utilities #:force-ll))

(in-package :cram-plans-tests.bad-input)

(def-suite bad-input :in cram-plans-tests:all
  :description "Bad input at every layer a user touches: clear errors or documented failures.")

(in-suite bad-input)

;;; ---- the table and its runner -----------------------------------------------------------

(defstruct (bad-case (:constructor make-bad-case (name layer expect form thunk match class)))
  name layer expect form thunk match class)

(defvar *cases* '() "The cases, newest first.")

(defun register-case (name layer expect form thunk match class)
  (setf *cases* (cons (make-bad-case name layer expect form thunk match class)
                      (remove name *cases* :key #'bad-case-name))))

(defmacro defcases (layer &body specs)
  "Define cases of LAYER. Each spec is (NAME EXPECT FORM &key MATCH CLASS): MATCH is the text
the error message must contain (case-insensitively), CLASS a condition class it must be of."
  `(progn
     ,@(loop for (name expect form . options) in specs
             collect `(register-case ',name ,layer ,expect ',form (lambda () ,form)
                                     ,(getf options :match) ',(getf options :class)))))

(defparameter *raw-condition-types*
  '(type-error arithmetic-error control-error storage-condition undefined-function
    unbound-variable unbound-slot program-error package-error stream-error reader-error
    print-not-readable file-error sb-sys:interactive-interrupt sb-ext:timeout
    sb-int:simple-program-error)
  "Condition types that are SBCL's own report of a fault, never a clear answer to bad input.")

(defun raw-condition-p (c)
  (or (some (lambda (type) (ignore-errors (typep c type))) *raw-condition-types*)
      (let ((nam (find-class 'sb-pcl::no-applicable-method-error nil)))
        (and nam (typep c nam)))
      (let ((name (symbol-name (class-name (class-of c)))))
        (search "NO-APPLICABLE-METHOD" name))))

(defun condition-text (c)
  (let ((*print-length* 20) (*print-level* 6))
    (handler-case (princ-to-string c)
      (error () (format nil "<unprintable ~s>" (type-of c))))))

(defun handle-number-p (text)
  "True when TEXT mentions an internal handle number (`handle 12')."
  (let ((i (search "handle " text :test #'char-equal)))
    (and i (< (+ i 7) (length text)) (digit-char-p (char text (+ i 7))))))

(defvar *case-timeout* 60 "Seconds a case may take before it counts as a hang (a crash).")

(defun run-bad-case (c)
  "Run the case C; return its outcome (:clear-error :failure :accepted :warned :vague :crash)
and a text describing what happened."
  (let ((warned nil) (result nil) (condition nil) (crash nil))
    (handler-case
        (handler-bind ((warning (lambda (w)
                                  (setf warned (or warned (condition-text w)))
                                  (muffle-warning w))))
          (let ((prolog:*break-on-lisp-errors* nil))
           (sb-sys:with-deadline (:seconds *case-timeout*)
            (setf result (multiple-value-list (funcall (bad-case-thunk c)))))))
      (storage-condition (s) (setf crash (format nil "~s: ~a" (type-of s) (condition-text s))))
      (sb-sys:deadline-timeout () (setf crash "timed out"))
      (serious-condition (s) (setf condition s)))
    (let ((expect (bad-case-expect c)))
      (cond
        (crash (values :crash crash))
        (condition
         (let ((text (condition-text condition))
               (match (bad-case-match c))
               (class (bad-case-class c)))
           (cond ((not (eq expect :error))
                  (values :vague (format nil "unexpected ~s: ~a" (type-of condition) text)))
                 ((raw-condition-p condition)
                  (values :vague (format nil "raw ~s: ~a" (type-of condition) text)))
                 ((and match (not (search match text :test #'char-equal)))
                  (values :vague (format nil "~s does not name ~s: ~a" (type-of condition)
                                         match text)))
                 ((and class (not (typep condition class)))
                  (values :vague (format nil "~s is not a ~s: ~a" (type-of condition) class text)))
                 ((handle-number-p text)
                  (values :vague (format nil "names a handle number: ~a" text)))
                 (t (values :clear-error text)))))
        ((eq expect :fails)
         (if (null (first result))
             (values :failure "NIL")
             (values :vague (format nil "returned ~s" result))))
        ((eq expect :accepts) (values :accepted (format nil "~s" result)))
        ((eq expect :warns)
         (if warned
             (values :warned warned)
             (values :vague (format nil "no warning, returned ~s" result))))
        (t (values :vague (format nil "no error (silence), returned ~s"
                                  (let ((*print-length* 5) (*print-level* 3)) (format nil "~s" result)))))))))

(defparameter *expected-outcome*
  '(:error :clear-error :fails :failure :accepts :accepted :warns :warned))

(defun run-bad-input-cases (&key (stream *standard-output*) layer)
  "Run every case (of LAYER when given); print the vague ones and the counts to STREAM.
Returns the list of (case outcome text)."
  (let ((results '()))
    (dolist (c (reverse *cases*))
      (when (or (null layer) (eq layer (bad-case-layer c)))
        (multiple-value-bind (outcome text) (run-bad-case c)
          (push (list c outcome text) results))))
    (setf results (nreverse results))
    (flet ((count-of (outcome) (count outcome results :key #'second)))
      (dolist (r results)
        (unless (eq (second r) (getf *expected-outcome* (bad-case-expect (first r))))
          (format stream "~&bad-input ~(~a~) ~s: ~(~a~): ~a~%" (bad-case-layer (first r))
                  (bad-case-name (first r)) (second r) (third r))))
      (format stream "~&bad-input: ~d cases, ~d clear errors, ~d documented failures, ~
~d accepted, ~d corrected with a warning, crashes=~d, vague=~d~%"
              (length results) (count-of :clear-error) (count-of :failure) (count-of :accepted)
              (count-of :warned) (count-of :crash) (count-of :vague))
      (finish-output stream))
    results))

(test bad-input-cases
  (let ((threads (busy-thread-count)))
    (dolist (r (run-bad-input-cases))
      (destructuring-bind (c outcome text) r
        (is (eq (getf *expected-outcome* (bad-case-expect c)) outcome)
            "~(~a~) case ~s ~s: expected ~(~a~), got ~(~a~): ~a"
            (bad-case-layer c) (bad-case-name c) (bad-case-form c)
            (bad-case-expect c) outcome text)))
    (sleep 0.2)
    (is (<= (busy-thread-count) threads)
        "no thread of the cases remains: ~d before, ~d after" threads
        (busy-thread-count))))

;;; ---- helpers ----------------------------------------------------------------------------

(defun busy-thread-count ()
  "The number of threads, without the task threads waiting for a task."
  (count cpl:*idle-task-thread-name* (sb-thread:list-all-threads)
         :key #'sb-thread:thread-name :test-not #'equal))

(defun nan () (sb-kernel:make-double-float -524288 0))
(defun inf () sb-ext:double-float-positive-infinity)

(defun deep-term (n &optional (leaf 'z))
  (let ((x leaf)) (dotimes (i n x) (setf x (list 's x)))))

(defun interpret (form)
  "Evaluate FORM with the interpreter, so that an error of a macro's expansion is signalled as
it is (the compiler would wrap it in a COMPILED-PROGRAM-ERROR)."
  (let ((sb-ext:*evaluator-mode* :interpret)) (eval form)))

(defun bad-input-checked-double (x)
  "A query helper: its errors make the goal fail (warn-and-fail, the default)."
  (unless (numberp x) (error "BAD-INPUT-CHECKED-DOUBLE: ~s is not a number" x))
  (* 2 x))

(defun bad-input-checked-triple (x)
  "A command helper registered with PROPAGATE-LISP-ERRORS: its errors leave the query."
  (unless (numberp x) (error "BAD-INPUT-CHECKED-TRIPLE: ~s is not a number" x))
  (* 3 x))

(prolog:propagate-lisp-errors 'bad-input-checked-triple)

(defun query (goal &optional bindings)
  "All solutions of GOAL."
  (force-ll (prolog goal bindings)))

(defun threads-after (thunk)
  "Call THUNK; signal its error only after checking that no thread it started remains."
  (let ((before (busy-thread-count)))
    (unwind-protect (funcall thunk)
      (sleep 0.05)
      (let ((after (busy-thread-count)))
        (when (> after before)
          (error "~d thread~:p left behind" (- after before)))))))

(def-fact-group bad-input-runaway ()
  (<- (bad-grow ?x) (bad-grow (s ?x)) (prolog:true))
  (<- (bad-par a b))
  (<- (bad-anc ?x ?y) (bad-anc ?x ?z) (bad-par ?z ?y))
  (<- (bad-nat 0))
  (<- (bad-nat (s ?x)) (bad-nat ?x))
  (<- (bad-loop-cp) (bad-loop-cp) (prolog:true))
  (<- (bad-loop-cp)))

(def-fact-group bad-input-owner ()
  (<- (bad-owned 1)))

;;; ---- Prolog -----------------------------------------------------------------------------

(defcases :prolog
  (runaway-growing-term :error (query '(bad-grow z)) :class prolog:prolog-resource-error)
  (runaway-left-recursion :error (query '(bad-anc a ?y)) :class prolog:prolog-resource-error)
  (runaway-choice-points :error (query '(bad-loop-cp)) :class prolog:prolog-resource-error)
  (endless-solutions-forced :error (length (query '(bad-nat ?x)))
   :class prolog:prolog-resource-error)
  (image-healthy-after-runaway :accepts
   (progn (ignore-errors (query '(bad-grow z))) (assert (equal '(nil) (query '(prolog:true))))))
  (deep-term-unify-1e5 :error (query `(prolog:== ?x ,(deep-term 100000)))
   :class prolog:prolog-resource-error)
  (deep-term-unify-1e6 :error (query `(prolog:== ,(deep-term 1000000) ,(deep-term 1000000)))
   :class prolog:prolog-resource-error)
  (deep-term-bindings :error (query '(prolog:== ?x ?y) `((?x . ,(deep-term 1000000))
                                                         (?y . ,(deep-term 1000000))))
   :class prolog:prolog-resource-error)
  (deep-term-ground :error (query `(prolog:ground ,(deep-term 1000000)))
   :class prolog:prolog-resource-error)
  (deep-term-copy-findall :error (query `(prolog:findall ?x (member ?x (,(deep-term 1000000))) ?l))
   :class prolog:prolog-resource-error)
  (deep-term-lisp-fun :error (query `(prolog:lisp-fun identity ,(deep-term 1000000) ?l))
   :class prolog:prolog-resource-error)
  (dotted-and :error (query '(and . 3)) :match "3")
  (dotted-or :error (query '(or (prolog:true) . foo)) :match "FOO")
  (goal-number :error (query 42) :match "42")
  (goal-string :error (query "member") :match "\"member\"")
  (goal-in-and-number :error (query '(and (prolog:true) 3)) :match "3")
  (functor-string :error (query '("foo" 1)) :match "\"foo\"")
  (functor-variable :error (query '(?f 1)) :match "?F")
  (compare-unbound :error (query '(> ?x 1)) :match "unbound")
  (compare-symbol :error (query '(> foo 1)) :match "FOO")
  (compare-string :error (query '(< 1 "a")) :match "\"a\"")
  (compare-list :error (query '(>= (1 2) 1)) :match "(1 2)")
  (compare-unbound-right :error (query '(<= 1 ?y)) :match "unbound")
  (compare-nan :error (query `(< ,(nan) 1)) :match "NaN")
  (not-without-goal :error (query '(not)) :match "NOT")
  (if-then-without-then :error (query '(prolog:-> (prolog:true))) :match "->")
  (if-then-too-many :error (query '(prolog:-> (prolog:true) (prolog:true) (prolog:true) (prolog:true)))
   :match "->")
  (call-unbound :error (query '(prolog:call ?g)) :match "?G")
  (call-number :error (query '(prolog:call 42)) :match "42")
  (findall-arity :error (query '(prolog:findall ?x)) :match "FINDALL")
  (not-number :error (query '(not 3)) :match "3")
  (once-number :error (query '(prolog:once 7)) :match "7")
  (bindings-not-alist :error (prolog '(prolog:true) 42) :match "42")
  (bindings-not-var :error (prolog '(prolog:true) '((x . 1))) :match "X")
  (undefined-predicate :fails (query '(bad-input-no-such-predicate 1)))
  (member-of-number :fails (query '(member ?x 3)))
  (lisp-fun-undefined :error (query '(prolog:lisp-fun bad-input-no-such-function 1 ?x))
   :match "BAD-INPUT-NO-SUCH-FUNCTION")
  (lisp-pred-bad-args :fails (query '(prolog:lisp-pred evenp foo)))
  (lisp-fun-query-error-fails :fails (query '(prolog:lisp-fun bad-input-checked-double foo ?x)))
  (lisp-fun-propagating-error :error
   (query '(prolog:lisp-fun bad-input-checked-triple foo ?x)) :match "FOO")
  (symbol-value-number :error (query '(symbol-value 42 ?v)) :match "42")
  (set-symbol-value-number :error (query '(prolog:set-symbol-value 42 1)) :match "42")
  (length-negative :error (query '(length ?l -1)) :match "-1")
  (length-improper :error (query '(length (1 2 . 3) ?n)) :match "(1 2 . 3)")
  (take-negative :error (query '(prolog:take -1 (1 2) ?x)) :match "-1")
  (max-of-symbols :fails (query '(max (a b) ?m)))
  (sort-mixed :accepts (query '(sort (3 a "b" 1) ?s)))
  (reduce-bad :fails (query '(reduce + (1 a) ?r)))
  (format-number-control :fails (query '(format 42)))
  (instance-of-unknown-class :fails (query '(prolog:instance-of bad-input-no-such-class ?o)))
  (fact-group-redefines-builtin :error
   (eval '(def-fact-group bad-input-builtin () (<- (member ?x ?y) (prolog:fail))))
   :match "MEMBER" :class prolog:fact-group-error)
  (fact-group-takes-foreign-functor :error
   (eval '(def-fact-group bad-input-thief () (<- (bad-owned 2))))
   :match "BAD-OWNED" :class prolog:fact-group-error)
  (fact-group-malformed-clause :error
   (eval '(def-fact-group bad-input-malformed () (<- 42)))
   :match "42")
  (fact-group-variable-head :error
   (eval '(def-fact-group bad-input-var-head () (<- (?p 1))))
   :match "?P")
  (fact-group-body-number :error
   (progn (eval '(def-fact-group bad-input-body-number () (<- (bad-body) 42)))
          (unwind-protect (query '(bad-body)) (prolog:remove-fact-group 'bad-input-body-number)))
   :match "42")
  (var-value-not-alist :error (cut:var-value '?x 42) :match "42")
  (force-ll-number :error (force-ll 42) :match "42")
  (lazy-car-string :error (cut:lazy-car "abc") :match "abc"))

;;; ---- plan language ----------------------------------------------------------------------

(defcases :cpl
  (return-from-par-child :error
   (threads-after (lambda () (cpl:top-level (block b (cpl:par (return-from b :early) (sleep 5))))))
   :class cpl:task-exit-error :match "par child")
  (return-from-outside-top-level :error
   (threads-after (lambda () (block b (cpl:top-level (cpl:par (return-from b :early) (sleep 5))))))
   :class cpl:task-exit-error)
  (throw-outside-top-level :error
   (threads-after (lambda () (catch 'outside (cpl:top-level (cpl:par (throw 'outside 1) (sleep 5))))))
   :class cpl:task-exit-error :match "OUTSIDE")
  ;; a top-level called from a thread that runs no task runs in that thread: a throw out of
  ;; its own body to the caller's catch unwinds it as in Lisp, and no thread is left behind
  (throw-from-top-level-body :accepts
   (threads-after (lambda () (catch 'outside (cpl:top-level (throw 'outside 1))))))
  (go-out-of-pursue :error
   (threads-after (lambda () (tagbody (cpl:top-level (cpl:pursue (go out) (sleep 5))) out)))
   :class cpl:task-exit-error)
  (return-from-try-all :error
   (threads-after (lambda () (cpl:top-level (block b (cpl:try-all (return-from b 1))))))
   :match "non-local exit")
  (exit-inside-task-works :accepts
   (progn (assert (eql 3 (cpl:top-level (block b (return-from b 3)))))
          (assert (eql 2 (cpl:top-level (catch 'in (cpl:par (catch 'in2 (throw 'in2 1))) (throw 'in 2)))))))
  (lisp-error-in-child :error (cpl:top-level (cpl:par (error "bad-input boom ~a" 17) (sleep 5)))
   :match "boom 17")
  (fail-bogus-initarg :error
   (cpl:top-level (cpl:fail 'common-fail:navigation-pose-unreachable :bogus-initarg 1))
   :match "BOGUS-INITARG")
  (fail-bogus-initarg-outside :error
   (cpl:fail 'common-fail:navigation-pose-unreachable :bogus-initarg 1) :match "BOGUS-INITARG")
  (fail-number :error (cpl:fail 42) :match "42")
  (fail-unknown-class :error (cpl:fail 'bad-input-no-such-failure) :match "BAD-INPUT-NO-SUCH-FAILURE")
  (fail-odd-initargs :error (cpl:fail 'common-fail:navigation-pose-unreachable :description)
   :match ":DESCRIPTION")
  (par-outside-top-level :error (cpl:par 1 2) :class cpl:not-inside-plan-error)
  (nested-top-level :error (cpl:top-level (cpl:top-level 1)) :match "top-level")
  (retry-counter-negative :error (interpret '(cpl:with-retry-counters ((n -1)) 1)) :match "-1")
  (retry-counter-unknown :error (interpret '(cpl:with-retry-counters ((n 1)) (cpl:do-retry bad-input-m 1)))
   :match "BAD-INPUT-M")
  (failure-handling-bad-clause :error (interpret '(cpl:with-failure-handling (42) 1)) :match "42")
  (make-fluent-bad-name :error (cpl:make-fluent :name 42) :match "42")
  (wait-for-true-value :accepts (cpl:top-level (cpl:wait-for 42)))
  (pulse-number :error (cpl:pulse 42) :match "42")
  (setf-value-derived :error (setf (cpl:value (cpl:fl+ (cpl:make-fluent :value 1) 1)) 2)
   :match "value fluent")
  (fl-apply-number :error (cpl:fl-apply 42 (cpl:make-fluent :value 1)) :match "42")
  (try-each-in-order-number :error (cpl:top-level (cpl:try-each-in-order (x 42) x)) :match "42")
  (sleep-negative :error (cpl:sleep -1) :match "-1")
  (sleep-nan :error (cpl:sleep (nan)) :match "NaN")
  (sleep-string :error (cpl:sleep "1") :match "\"1\"")
  (log-level-unknown :error (let ((cpl:*log-level* :bogus-level)) (cpl:log-info "x")) :match "BOGUS-LEVEL")
  (log-format-number :error (cpl:log-message :info nil 42) :match "42")
  (goal-undeclared :error (interpret '(cpl:def-goal (bad-input-no-such-goal ?x) ?x))
   :match "BAD-INPUT-NO-SUCH-GOAL")
  (task-tree-html-bad-path :error (cpl:write-task-tree-html 42) :match "42"))

;;; ---- transforms -------------------------------------------------------------------------

(defcases :transforms
  (vector-string :error (cl-transforms:make-3d-vector 1 2 "3") :match "\"3\"")
  (vector-nan :error (cl-transforms:make-3d-vector (nan) 0 0) :match "NaN")
  (vector-inf :error (cl-transforms:make-3d-vector 0 (inf) 0) :match "INFINITY")
  (vector-bignum :error (cl-transforms:make-3d-vector (expt 10 400) 0 0) :match "1000000")
  (v+-overflow :error (cl-transforms:v+ (cl-transforms:make-3d-vector 1d308 1d308 0)
                                        (cl-transforms:make-3d-vector 1d308 1d308 0))
   :match "1.0d308")
  (v--overflow :error (cl-transforms:v- (cl-transforms:make-3d-vector -1d308 0 0)
                                        (cl-transforms:make-3d-vector 1d308 0 0))
   :match "1.0d308")
  (v*-overflow :error (cl-transforms:v* (cl-transforms:make-3d-vector 1d308 0 0) 10) :match "1.0d308")
  (v*-nan :error (cl-transforms:v* (cl-transforms:make-3d-vector 1 0 0) (nan)) :match "NaN")
  (v/-zero :error (cl-transforms:v/ (cl-transforms:make-3d-vector 1 0 0) 0) :match "0")
  (dot-overflow :error (cl-transforms:dot-product (cl-transforms:make-3d-vector 1d200 0 0)
                                                  (cl-transforms:make-3d-vector 1d200 0 0))
   :match "1.0d200")
  (cross-overflow :error (cl-transforms:cross-product (cl-transforms:make-3d-vector 1d200 0 0)
                                                      (cl-transforms:make-3d-vector 0 1d200 0))
   :match "1.0d200")
  (norm-overflow :accepts (cl-transforms:v-norm (cl-transforms:make-3d-vector 1d200 1d200 0)))
  (normalize-zero :error (cl-transforms:normalize-vector (cl-transforms:make-3d-vector 0 0 0))
   :match "0")
  (v+-number :error (cl-transforms:v+ 42 (cl-transforms:make-3d-vector 0 0 0)) :match "42")
  (quaternion-huge-normalised :accepts
   (assert (< (abs (- (cl-transforms:x (cl-transforms:make-quaternion 1d200 1d200 0 0)) (sqrt 0.5d0))) 1d-12)))
  (quaternion-zero :error (cl-transforms:make-quaternion 0 0 0 0) :match "0")
  (quaternion-nan :error (cl-transforms:make-quaternion (nan) 0 0 1) :match "NaN")
  (axis-angle-zero-axis :error (cl-transforms:axis-angle->quaternion
                                (cl-transforms:make-3d-vector 0 0 0) 1)
   :match "0")
  (axis-angle-huge-angle :accepts (cl-transforms:axis-angle->quaternion
                                   (cl-transforms:make-3d-vector 0 0 1) 1d300))
  (euler-huge :accepts (cl-transforms:euler->quaternion :ax 1d300))
  (euler-string :error (cl-transforms:euler->quaternion :az "1") :match "\"1\"")
  (q*-number :error (cl-transforms:q* (cl-transforms:make-identity-rotation) 42) :match "42")
  (pose-number :error (cl-transforms:make-pose 42 (cl-transforms:make-identity-rotation)) :match "42")
  (pose-nil-orientation :error (cl-transforms:make-pose (cl-transforms:make-3d-vector 0 0 0) nil)
   :match "NIL")
  (pose-stamped-empty-frame :error
   (cl-transforms-stamped:make-pose-stamped "" 0 (cl-transforms:make-3d-vector 0 0 0)
                                            (cl-transforms:make-identity-rotation))
   :match "\"\"")
  (pose-stamped-number-frame :error
   (cl-transforms-stamped:make-pose-stamped 42 0 (cl-transforms:make-3d-vector 0 0 0)
                                            (cl-transforms:make-identity-rotation))
   :match "42")
  (pose-stamped-string-stamp :error
   (cl-transforms-stamped:make-pose-stamped "map" "now" (cl-transforms:make-3d-vector 0 0 0)
                                            (cl-transforms:make-identity-rotation))
   :match "\"now\"")
  (pose-stamped-nan-stamp :error
   (cl-transforms-stamped:make-pose-stamped "map" (nan) (cl-transforms:make-3d-vector 0 0 0)
                                            (cl-transforms:make-identity-rotation))
   :match "NaN")
  (transform-point-number :error (cl-transforms:transform-point (cl-transforms:make-identity-transform) 42)
   :match "42")
  (transform-pose-overflow :error
   (cl-transforms:transform-pose (cl-transforms:make-transform (cl-transforms:make-3d-vector 1d308 0 0)
                                                               (cl-transforms:make-identity-rotation))
                                 (cl-transforms:make-pose (cl-transforms:make-3d-vector 1d308 0 0)
                                                          (cl-transforms:make-identity-rotation)))
   :match "1.0d308")
  (matrix-not-square :error (cl-transforms:matrix->quaternion #2A((1 2) (3 4))) :match "#2A")
  (normalize-angle-nan :error (cl-transforms:normalize-angle (nan)) :match "NaN")
  (normalize-angle-huge :accepts (cl-transforms:normalize-angle 1d300))
  (slerp-nan :error (cl-transforms:slerp (cl-transforms:make-identity-rotation)
                                         (cl-transforms:make-identity-rotation) (nan))
   :match "NaN")
  (interpolate-string :error (cl-transforms:interpolate-vector (cl-transforms:make-3d-vector 0 0 0)
                                                               (cl-transforms:make-3d-vector 1 0 0) "half")
   :match "\"half\"")
  (lookup-unknown-frame :error
   (cl-transforms-stamped:lookup-transform (make-instance 'cl-transforms-stamped:transformer)
                                           "map" "bad_input_frame")
   :match "bad_input_frame")
  (set-transform-number :error
   (cl-transforms-stamped:set-transform (make-instance 'cl-transforms-stamped:transformer) 42)
   :match "42")
  (translate-pose-number :error (cram-tf:translate-pose 42 :x-offset 1) :match "42"))

;;; ---- designators ------------------------------------------------------------------------

(defcases :designators
  (action-unknown-property :error
   (desig:reference (desig:an action (type picking-up) (colour red))) :match "COLOUR")
  (location-pose-string :error
   (desig:reference (desig:a location (pose "not-a-pose"))) :match "not-a-pose")
  (location-pose-number :error (desig:reference (desig:a location (pose 42))) :match "42")
  (unknown-designator-kind :error (desig:make-designator :bad-input-kind '((type x)))
   :match "BAD-INPUT-KIND")
  (description-number :error (desig:make-designator :action 42) :match "42")
  (description-bad-property :error (desig:make-designator :action '(type)) :match "TYPE")
  (prop-value-number :error (desig:desig-prop-value 42 :type) :match "42")
  (reference-number :error (desig:reference 42) :match "42")
  (reference-string :error (desig:reference "a bottle") :match "a bottle")
  (equate-number :error (desig:equate 42 (desig:an object (type bottle))) :match "42")
  (copy-number :error (desig:copy-designator 42) :match "42")
  (next-solution-number :error (desig:next-solution 42) :match "42")
  (motion-unknown-type :error (desig:reference (desig:a motion (type bad-input-motion)))
   :match "BAD-INPUT-MOTION")
  (action-unknown-type :error (desig:reference (desig:an action (type bad-input-action)))
   :match "BAD-INPUT-ACTION")
  (action-without-type :error (desig:reference (desig:an action (arm left))) :match "ARM")
  (object-unknown-property-ok :accepts (desig:an object (type bottle) (shade red)))
  (update-properties-number :error (desig:update-designator-properties 42 '((type x)))
   :match "42")
  (a-macro-malformed :error (interpret '(desig:a location 42)) :match "42"))
