;;;; Tests of the designator-type index of Prolog clauses (PROLOG:REGISTER-FIRST-GOAL-GUARD,
;;;; registered by the designators for DESIG-PROP): a predicate whose clauses begin with
;;;; (desig-prop ?d (:type :a-type)) gives the same solutions, in the same order, with the
;;;; index as without it, for every kind of first argument.

(in-package :cram-designators-tests)

(in-suite designators)

(prolog:def-fact-group designators-test-type-index (type-index-test)
  (prolog:<- (type-index-test ?d :going-1)
    (desig:desig-prop ?d (:type :going)))
  (prolog:<- (type-index-test ?d :any-type)
    (desig:desig-prop ?d (:type ?type)))
  (prolog:<- (type-index-test ?d :looking)
    (desig:desig-prop ?d (:type :looking)))
  (prolog:<- (type-index-test :an-atom :atom))
  (prolog:<- (type-index-test ?d :going-2)
    (desig:desig-prop ?d (:type :going))
    (desig:desig-prop ?d (:speed ?_)))
  (prolog:<- (type-index-test ?d :unguarded)
    (prolog:lisp-pred identity ?d))
  (prolog:<- (type-index-test ?d :string-type)
    (desig:desig-prop ?d (:type "going"))))

(defun type-index-answers (first-argument)
  (mapcar (lambda (b) (cut:var-value '?r b))
          (cut:force-ll (prolog:prolog `(type-index-test ?x ?r) `((?x . ,first-argument))))))

(defun without-type-index (thunk)
  "THUNK's value with the designator-type index taken out of the database, restored after."
  (let ((saved prolog::*first-goal-guards*))
    (unwind-protect (progn (setf prolog::*first-goal-guards* '())
                           (prolog::reselect-all-clauses)
                           (funcall thunk))
      (setf prolog::*first-goal-guards* saved)
      (prolog::reselect-all-clauses))))

(test designator-type-index-keeps-every-answer-in-order
  (let ((arguments (list (desig:a motion (type going))
                         (desig:a motion (type going) (speed 1))
                         (desig:a motion (type looking))
                         (desig:a motion (type detecting))
                         (desig:make-designator :motion '((:type :going) (:type :looking)))
                         (desig:make-designator :motion '((:type "going")))
                         (desig:make-designator :motion '((:speed 1)))
                         (desig:make-designator :motion '((:type ?some-variable)))
                         (desig:make-designator :motion (list (list :type (vector 1 2))))
                         :an-atom :another-atom 42 "text" (list 1 2))))
    (is (member 'desig:desig-prop prolog::*first-goal-guards*
                :key #'prolog::first-goal-guard-functor))
    (let ((indexed (mapcar #'type-index-answers arguments))
          (plain (without-type-index (lambda () (mapcar #'type-index-answers arguments)))))
      (is (equal plain indexed))
      ;; what the rules promise, so that the comparison is not of two empty lists
      (is (equal '(:going-1 :any-type :unguarded) (first indexed)))
      (is (equal '(:going-1 :any-type :going-2 :unguarded) (second indexed)))
      (is (equal '(:any-type :looking :unguarded) (third indexed)))
      (is (equal '(:any-type :unguarded) (fourth indexed)))
      (is (equal '(:going-1 :any-type :any-type :looking :unguarded) (fifth indexed)))
      (is (equal '(:any-type :unguarded :string-type) (sixth indexed)))
      (is (equal '(:atom :unguarded) (nth 9 indexed)))
      (is (eq :all (desig::designator-type-key (nth 8 arguments))))
      (is (eq :all (desig::designator-type-key (nth 4 arguments))))
      (is (eq :going (desig::designator-type-key (first arguments))))
      (is (null (desig::designator-type-key (nth 6 arguments)))))))

;;; A guard of the test's own, which counts the goals it runs: the index passes the clauses
;;; over without running their guards.

(defstruct guard-test-thing kind)

(defvar *guard-goals-run* 0)

(defun guard-test-kind-p (thing kind)
  (incf *guard-goals-run*)
  (and (guard-test-thing-p thing) (eq (guard-test-thing-kind thing) kind)))

(prolog:def-fact-group designators-test-counted-guard (guard-test-kind guard-test-rule)
  (prolog:<- (guard-test-kind ?thing ?kind)
    (prolog:lisp-pred guard-test-kind-p ?thing ?kind))
  (prolog:<- (guard-test-rule ?x :a) (guard-test-kind ?x :a))
  (prolog:<- (guard-test-rule ?x :b) (guard-test-kind ?x :b))
  (prolog:<- (guard-test-rule ?x :c) (guard-test-kind ?x :c))
  (prolog:<- (guard-test-rule ?x :any) (prolog:lisp-pred identity ?x)))

(defun guard-test-answers (thing)
  (let ((*guard-goals-run* 0))
    (values (mapcar (lambda (b) (cut:var-value '?r b))
                    (cut:force-ll (prolog:prolog `(guard-test-rule ,thing ?r))))
            *guard-goals-run*)))

(test first-goal-guard-passes-over-the-clauses-it-rules-out
  (let ((b (make-guard-test-thing :kind :b))
        (other (make-guard-test-thing :kind :d)))
    ;; without the guard registered every rule runs its guard goal
    (multiple-value-bind (answers goals) (without-type-index (lambda () (guard-test-answers b)))
      (is (equal '(:b :any) answers))
      (is (= 3 goals)))
    (let ((saved prolog::*first-goal-guards*))
      (unwind-protect
           (progn
             (prolog:register-first-goal-guard
              'guard-test-kind
              (lambda (args) (and (keywordp (first args)) (null (rest args)) (first args)))
              (lambda (object) (if (guard-test-thing-p object) (guard-test-thing-kind object) :all)))
             (multiple-value-bind (answers goals) (guard-test-answers b)
               (is (equal '(:b :any) answers))
               (is (= 1 goals)))
             (multiple-value-bind (answers goals) (guard-test-answers other)
               (is (equal '(:any) answers))
               (is (= 0 goals)))
             ;; an object the guard does not know: every clause, as without the index
             (multiple-value-bind (answers goals) (guard-test-answers :some-atom)
               (is (equal '(:any) answers))
               (is (= 3 goals)))
             ;; keys compare with EQUAL: strings made afresh for each call match
             (prolog:register-first-goal-guard
              'guard-test-kind
              (lambda (args) (and (keywordp (first args)) (copy-seq (symbol-name (first args)))))
              (lambda (object) (if (guard-test-thing-p object)
                                   (copy-seq (symbol-name (guard-test-thing-kind object)))
                                   :all)))
             (multiple-value-bind (answers goals) (guard-test-answers b)
               (is (equal '(:b :any) answers))
               (is (= 1 goals))))
        (setf prolog::*first-goal-guards* saved)
        (without-type-index (constantly nil))))))

(test first-goal-guard-rejects-a-bad-functor
  (signals type-error (prolog:register-first-goal-guard "desig-prop" #'identity #'identity)))
