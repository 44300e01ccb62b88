;;;; Tests of the fact engine (PROLOG): queries, fact groups, control, cut, laziness, handlers.

(defpackage :cram-prolog-tests
  (:use :cl :fiveam :cram-prolog :cram-utilities)
  (:shadowing-import-from :cram-prolog #:fail)
  ;; the shop knowledge base below has a functor TYPE; the Pepper demo defines the same
  ;; knowledge base with CL:TYPE, so these tests keep theirs apart
  (:shadow #:type))

(in-package :cram-prolog-tests)

(def-suite prolog :in cram-plans-tests:all :description "The CRAM-dialect fact engine.")
(in-suite prolog)

(defun all (goal &optional bindings)
  "Every solution of GOAL as a list of binding alists."
  (force-ll (prolog goal bindings)))

(defun values-of (var goal &optional bindings)
  "The value of VAR in every solution of GOAL."
  (mapcar (lambda (b) (var-value var b)) (all goal bindings)))

;;; The shop knowledge base of the Pepper shop tutorial

(def-fact-group product-type-predicates ()
  (<- (is-of-type ?product ?type)
    (is-type ?product ?type)
    (product ?product)
    (type ?type))
  (<- (product cereal))
  (<- (product milk))
  (<- (product bowl))
  (<- (type :breakfast-cereal))
  (<- (type :milk))
  (<- (is-type cereal :breakfast-cereal))
  (<- (is-type milk :milk)))

(def-fact-group shelf-product-predicates ()
  (<- (is-on-shelf ?object ?shelf)
    (is-on ?object ?shelf)
    (object ?object)
    (shelf ?shelf))
  (<- (is-on-shelf ?object)
    (is-on ?object ?shelf)
    (shelf ?shelf))
  (<- (shelf shelf-one-level-1)) (<- (shelf shelf-one-level-2)) (<- (shelf shelf-one-level-3))
  (<- (shelf shelf-one-level-4)) (<- (shelf shelf-one-level-5))
  (<- (shelf shelf-two-level-1)) (<- (shelf shelf-two-level-2)) (<- (shelf shelf-two-level-3))
  (<- (shelf shelf-two-level-4)) (<- (shelf shelf-two-level-5))
  (<- (object cereal)) (<- (object somat)) (<- (object milk)) (<- (object bowl))
  (<- (object denkmit))
  (<- (is-on cereal shelf-one-level-4))
  (<- (is-on cereal shelf-two-level-3))
  (<- (is-on cereal shelf-one-level-2))
  (<- (is-on somat shelf-one-level-2))
  (<- (is-on somat shelf-one-level-3))
  (<- (is-on somat shelf-one-level-4))
  (<- (is-on milk shelf-one-level-4))
  (<- (is-on milk shelf-two-level-4))
  (<- (is-on bowl shelf-two-level-1))
  (<- (is-on denkmit shelf-two-level-2)))

(def-fact-group shelf-location-predicates ()
  (<- (is-located-at ?shelfs ?location)
    (is-at ?shelfs ?location)
    (location ?location)
    (shelfs ?shelfs))
  (<- (shelfs shelf-one-level-4))
  (<- (shelfs shelf-two-level-3))
  (<- (location :|KITCHEN.shelf_1_level_4_link|))
  (<- (location :|KITCHEN.shelf_2_level_3_link|))
  (<- (is-at shelf-one-level-4 :|KITCHEN.shelf_1_level_4_link|))
  (<- (is-at shelf-two-level-3 :|KITCHEN.shelf_2_level_3_link|)))

(test seed-shop-all-solutions
  (is (equal '(((?object . cereal) (?shelf . shelf-one-level-4))
               ((?object . cereal) (?shelf . shelf-two-level-3))
               ((?object . cereal) (?shelf . shelf-one-level-2))
               ((?object . somat) (?shelf . shelf-one-level-2))
               ((?object . somat) (?shelf . shelf-one-level-3))
               ((?object . somat) (?shelf . shelf-one-level-4))
               ((?object . milk) (?shelf . shelf-one-level-4))
               ((?object . milk) (?shelf . shelf-two-level-4))
               ((?object . bowl) (?shelf . shelf-two-level-1))
               ((?object . denkmit) (?shelf . shelf-two-level-2)))
             (force-ll (prolog `(and (is-on-shelf ?object ?shelf)))))))

(test seed-shop-first-solution-is-lazy
  (let ((result (prolog '(and (is-on-shelf ?object ?shelf)))))
    (is (equal '((?object . cereal) (?shelf . shelf-one-level-4)) (lazy-car result)))
    (is (= 1 (expanded-length result)) "only the first solution is computed")))

(test seed-shop-other-queries
  (is (equal '(shelf-one-level-4 shelf-two-level-3 shelf-one-level-2)
             (values-of '?shelf `(and (is-on-shelf cereal ?shelf)))))
  (is (equal :|KITCHEN.shelf_1_level_4_link|
             (cdaar (force-ll (prolog `(and (is-located-at shelf-one-level-4 ?location)))))))
  (is (equal :milk (cdaar (force-ll (prolog `(and (is-of-type milk ?type)))))))
  (is (null (all '(is-of-type bowl ?type))))
  (is (equal '(cereal cereal cereal somat somat somat milk milk bowl denkmit)
             (values-of '?o '(is-on-shelf ?o)))
      "a functor with clauses of two arities"))

;;; Answers

(test answer-shapes
  (is (null (prolog '(product spoon))) "no solution is NIL")
  (is (equal '(nil) (all '(product milk))) "a solution binding nothing is (NIL)")
  (is (equal '(((?x . 1))) (all '(== ?x 1))))
  (is (equal '(((?x . (1 . 2)))) (all '(== ?x (1 . 2))))))

(test unbound-variables-in-answers
  (is (equal '(nil) (all '(== ?x ?x))) "an unbound variable is left out")
  (let ((b (car (all '(== ?x (f ?y))))))
    (is (equal '(f ?y) (var-value '?x b)))
    (is (eq '?y (var-value '?y b))))
  (let* ((b (car (all '(== ?x (g ?_)))))
         (v (var-value '?x b)))
    (is (eq 'g (first v)))
    (is (is-var (second v)) "an unbound inner variable appears as a ?symbol")))

(test initial-bindings
  (is (equal '(shelf-two-level-4) (values-of '?s '(is-on ?o ?s) '((?o . milk) (?s . shelf-two-level-4)))))
  (is (equal '(shelf-one-level-4 shelf-two-level-4) (values-of '?s '(is-on ?o ?s) '((?o . milk)))))
  (is (equal '(milk milk) (values-of '?o '(is-on ?o ?s) '((?o . milk)))) "initial variables are reported")
  (is (null (all '(is-on ?o ?s) '((?o . spoon)))))
  (signals prolog-error (prolog '(true) '(not-a-binding))))

(test reading-answers
  (let ((b (lazy-car (prolog '(is-on ?what shelf-two-level-1)))))
    (is (eq 'bowl (var-value '?what b)))
    (with-vars-bound (?what) b
      (let ((what ?what))
        (is (eq 'bowl what))))))

(test atoms-compare-with-equal
  (is (equal '(nil) (all '(== "abc" "abc"))))
  (is (null (all '(== "abc" "ABC"))))
  (is (null (all '(== 1 1.0))) "numbers of different types do not unify")
  (is (equal '(nil) (all '(== 2.5 2.5))))
  (let ((object (list :a)))
    (is (eq object (var-value '?x (car (all `(== ?x ,object))))))))

(test dotted-patterns-and-anonymous-variables
  (is (equal '(((?h . 1) (?t 2 3))) (all '(== (?h . ?t) (1 2 3)))))
  (is (equal '(nil) (all '(== (?_ ?_) (1 2)))) "each ?_ is a different variable")
  (is (null (all '(== (?a ?a) (1 2))))))

(def-fact-group rest-args ()
  (<- (first-of (?x . ?_) ?x))
  (<- (packed . ?args) (== ?args (1 2))))

(test dotted-clause-heads
  (is (equal '(a) (values-of '?f '(first-of (a b c) ?f))))
  (is (equal '(nil) (all '(packed 1 2))))
  (is (null (all '(packed 1)))))

;;; Fact groups

(def-fact-group order-base (ordered)
  (<- (ordered 1))
  (<- (ordered 2)))

(def-fact-group order-extension (ordered)
  (<- (ordered 3)))

(test clause-order-across-groups
  (is (equal '(1 2 3) (values-of '?x '(ordered ?x)))))

(test extendable-functor-error
  (eval '(def-fact-group conflict-a () (<- (conflict-pred 1))))
  (let ((e (handler-case (progn (eval '(def-fact-group conflict-b () (<- (conflict-pred 2)))) nil)
             (fact-group-error (e) e))))
    (is (typep e 'fact-group-error))
    (let ((text (princ-to-string e)))
      (is (search "CONFLICT-PRED" text))
      (is (search "CONFLICT-A" text))
      (is (search "CONFLICT-B" text))))
  (is (equal '(1) (values-of '?x '(conflict-pred ?x))) "the rejected group changed nothing"))

(test extendable-functor-allowed
  (eval '(def-fact-group iface-base () (<- (iface-pred ?x) (fail))))
  (eval '(def-fact-group iface-impl (iface-pred) (<- (iface-pred :impl))))
  (is (equal '(:impl) (values-of '?x '(iface-pred ?x))))
  (eval '(def-fact-group iface-open (open-pred) (<- (open-pred 1))))
  (signals fact-group-error (eval '(def-fact-group iface-open-user () (<- (open-pred 2))))
    "listed as extendable only by the group that defines it: CRAM's error")
  (eval '(def-fact-group iface-open-user (open-pred) (<- (open-pred 2))))
  (is (equal '(1 2) (values-of '?x '(open-pred ?x)))))

(test group-redefinition
  (eval '(def-fact-group redef-a () (<- (redef-pred 1))))
  (eval '(def-fact-group redef-b (redef-pred) (<- (redef-pred 2))))
  (is (equal '(1 2) (values-of '?x '(redef-pred ?x))))
  (eval '(def-fact-group redef-a () (<- (redef-pred 10)) (<- (redef-pred 11))))
  (is (equal '(10 11 2) (values-of '?x '(redef-pred ?x))) "replaced in place")
  (eval '(def-fact-group redef-a () (<- (other-redef-pred 1))))
  (is (equal '(2) (values-of '?x '(redef-pred ?x))) "functors no longer defined lose clauses")
  (is (remove-fact-group 'redef-b))
  (is (null (handler-bind ((warning #'muffle-warning)) (all '(redef-pred ?x))))))

(test clause-outside-group
  (signals prolog-error (eval '(<- (lonely 1))))
  (signals fact-group-error (macroexpand '(def-fact-group bad () (not-a-clause))))
  (signals fact-group-error (eval '(def-fact-group bad-head () (<- ("string-head" 1))))))

(test group-introspection
  (is (member 'shelf-product-predicates (fact-group-names)))
  (is (equal '(product cereal) (car (second (fact-group-clauses 'product-type-predicates)))))
  (signals fact-group-error (fact-group-clauses 'no-such-group))
  (is (= 3 (length (predicate-clauses 'ordered)))))

(test undefined-predicate-warns-once
  (let ((warnings 0)
        (functor (intern (symbol-name (gensym "UNDEFINED-THING-")))))
    (handler-bind ((warning (lambda (w)
                              (when (search (symbol-name functor) (princ-to-string w))
                                (incf warnings))
                              (muffle-warning w))))
      (is (null (all (list functor 1))))
      (is (null (all (list functor 2)))))
    (is (= 1 warnings))))

;;; Cut

(def-fact-group cut-tests ()
  (<- (cut-first ?x) (member ?x (1 2 3)) (cut))
  (<- (cut-first 99))
  (<- (cut-in-or ?x) (or (and (member ?x (1 2 3)) (cut)) (== ?x 10)))
  (<- (cut-in-or 20))
  (<- (no-cut ?x) (or (member ?x (1 2)) (== ?x 10)))
  (<- (no-cut 20))
  (<- (max-of ?a ?b ?a) (>= ?a ?b) (cut))
  (<- (max-of ?_ ?b ?b))
  (<- (cut-in-once ?x) (once (member ?x (1 2 3)) (cut)) (member ?y (a b)))
  (<- (cut-in-not ?x) (member ?x (1 2 3)) (not (and (== ?x 2) (cut) (fail)))))

(test cut-in-clause-body
  (is (equal '(1) (values-of '?x '(cut-first ?x))) "cut prunes the goals before it and later clauses")
  (is (equal '(5) (values-of '?m '(max-of 5 3 ?m))))
  (is (equal '(7) (values-of '?m '(max-of 5 7 ?m)))))

(test cut-inside-nested-or
  (is (equal '(1) (values-of '?x '(cut-in-or ?x))) "cut in an OR branch cuts the clause")
  (is (equal '(1 2 10 20) (values-of '?x '(no-cut ?x)))))

(test cut-is-local-in-once-and-not
  (is (equal '(1 1) (values-of '?x '(cut-in-once ?x))) "cut inside ONCE does not cut the clause")
  (is (equal '(1 2 3) (values-of '?x '(cut-in-not ?x))) "cut inside NOT does not cut the clause"))

(test cut-at-query-level
  (is (equal '(1) (values-of '?x '(and (member ?x (1 2 3)) (cut)))))
  (is (equal '((1 a) (1 b)) (mapcar (lambda (b) (list (var-value '?x b) (var-value '?y b)))
                                    (all '(and (member ?x (1 2)) (cut) (member ?y (a b))))))))

(test call-is-opaque-to-cut
  (is (equal '(1 2) (values-of '?x '(and (member ?x (1 2)) (call (cut)))))))

;;; Control

(test and-or-true-fail
  (is (equal '(nil) (all '(and))))
  (is (equal '(nil) (all '(true))))
  (is (null (all '(fail))))
  (is (null (all '(and (true) (fail)))))
  (is (equal '(1 2 3) (values-of '?x '(or (== ?x 1) (== ?x 2) (== ?x 3)))))
  (is (null (all '(or)))))

(test negation
  (is (equal '(nil) (all '(not (member 4 (1 2 3))))))
  (is (null (all '(not (member 2 (1 2 3))))))
  (is (equal '(((?x . 4))) (all '(and (== ?x 4) (not (member ?x (1 2 3))))))
      "NOT keeps the incoming bindings")
  (is (equal '(nil) (all '(not (== ?y 1) (== ?y 2))))
      "several goals are a conjunction")
  (is (null (all '(not (== ?y 1))))
      "NOT binds nothing and fails when its goal can succeed"))

(test if-then-else
  (is (equal '(((?x . 1) (?y . 1))) (all '(-> (member ?x (1 2 3)) (== ?y ?x) (== ?y none))))
      "commits to the first solution of the condition")
  (is (equal '(none) (values-of '?y '(-> (member 4 (1 2 3)) (== ?y found) (== ?y none)))))
  (is (null (all '(-> (fail) (true)))) "the else branch defaults to FAIL")
  (is (equal '(a b) (values-of '?y '(-> (true) (member ?y (a b)) (== ?y c))))
      "the then branch keeps its solutions"))

(test soft-cut
  (is (equal '((1 . 1) (2 . 2) (3 . 3))
             (mapcar (lambda (b) (cons (var-value '?x b) (var-value '?y b)))
                     (all '(*-> (member ?x (1 2 3)) (== ?y ?x) (== ?y none)))))
      "keeps every solution of the condition")
  (is (equal '(none) (values-of '?y '(*-> (fail) (== ?y found) (== ?y none))))))

(test once-and-call
  (is (equal '(1) (values-of '?x '(once (member ?x (1 2 3))))))
  (is (equal '(1 2) (values-of '?x '(and (== ?g (member ?x (1 2))) (call ?g)))))
  (is (equal '(1 2) (values-of '?x '(call member ?x (1 2)))) "CALL adds extra arguments")
  (is (equal '(2) (values-of '?x '(and (== ?g (and (member ?x (1 2)) (> ?x 1))) ?g)))
      "a variable goal is called")
  (signals prolog-error (all '(call ?unbound))))

(test findall-bagof-setof
  (is (equal '((1 2 3)) (values-of '?l '(findall ?x (member ?x (1 2 3)) ?l))))
  (is (equal '(nil) (values-of '?l '(findall ?x (fail) ?l))) "FINDALL of nothing is ()")
  (is (equal '(((1 . a) (2 . a))) (values-of '?l '(findall (?x . a) (member ?x (1 2)) ?l))))
  (is (null (all '(bagof ?x (fail) ?l))) "BAGOF fails without solutions")
  (is (equal '((b a b)) (values-of '?l '(bagof ?x (member ?x (b a b)) ?l))))
  (is (equal '((b a)) (values-of '?l '(setof ?x (member ?x (b a b)) ?l)))
      "SETOF removes duplicates, keeping the order")
  (is (equal '(nil) (all '(findall ?x (member ?x (1 2)) (1 2))))))

(test forall-and-every
  (is (equal '(nil) (all '(forall (member ?x (1 2 3)) (> ?x 0)))))
  (is (null (all '(forall (member ?x (1 2 3)) (> ?x 1)))))
  (is (equal '(ok) (values-of '?r '(every (member ?x (1 2 3)) (== ?r ok)))))
  (is (null (all '(every (member ?x (1 2 3)) (== ?r ?x)))) "values must stay the same")
  (is (null (all '(every (member ?x (1 2 3)) (> ?x 1))))))

(test findall-over-infinite-generator-with-take
  (let ((naturals (lazy-list ((i 0)) (cont i (1+ i)))))
    (is (equal '((0 1 2 3 4))
               (values-of '?l `(and (take 5 ?gen ?first) (findall ?x (member ?x ?first) ?l))
                          `((?gen . ,naturals)))))
    (is (equal '(3) (values-of '?x `(once (member ?x ?gen) (> ?x 2)) `((?gen . ,naturals)))))))

(test goals-with-bindings-compiled-once-when-asked-again
  "A constant goal asked repeatedly with initial bindings of the same variables is compiled once;
each query's bindings give its own solutions; other pre-bound variables compile it again."
  (let ((goal (list 'member '?x '?list))
        (compiles 0))
    (sb-int:encapsulate 'cram-prolog::compile-goal-term 'count
                        (lambda (f &rest args) (incf compiles) (apply f args)))
    (unwind-protect
         (progn
           (dotimes (i 20)
             (is (equal (list i (1+ i))
                        (mapcar (lambda (b) (cdr (assoc '?x b)))
                                (force-ll (prolog goal `((?list . (,i ,(1+ i))))))))))
           (is (<= compiles 2) "compiled ~d times for 20 queries" compiles)
           (setf compiles 0)
           (is (equal '(b) (mapcar (lambda (b) (cdr (assoc '?x b)))
                                   (force-ll (prolog goal '((?list . (a b)) (?x . b)))))))
           (is (= 1 compiles) "other pre-bound variables: compiled for them")
           (is (null (force-ll (prolog goal '((?list . (a b)) (?x . c))))))
           (is (equal '((?x . c) (?list . (c))) (first (force-ll (prolog goal '((?list . (c)))))))))
      (sb-int:unencapsulate 'cram-prolog::compile-goal-term 'count))))

(test the-same-query-built-afresh-is-compiled-once
  "A query built afresh for each call (a backquoted goal) that is EQUAL to one asked shortly
before reuses its compilation, is not kept in the table, and still sees the facts as they are."
  (let ((compiles 0)
        (before (hash-table-count cram-prolog::*compiled-goals*)))
    (sb-int:encapsulate 'cram-prolog::compile-goal-term 'count
                        (lambda (f &rest args) (incf compiles) (apply f args)))
    (unwind-protect
         (progn
           (dotimes (i 50)
             (let ((name (copy-seq "shelf")))
               (is (equal '((1 2) (3 4))
                          (mapcar (lambda (b) (list (cdr (assoc '?a b)) (cdr (assoc '?b b))))
                                  (force-ll (prolog `(member (?a ?b ,name) ((1 2 "shelf") (3 4 "shelf"))))))))))
           (is (<= compiles 1) "compiled ~d times for 50 equal queries" compiles)
           (is (<= (hash-table-count cram-prolog::*compiled-goals*) before))
           ;; an equal goal with other pre-bound variables, and another goal, are compiled
           (setf compiles 0)
           (is (equal '(3) (mapcar (lambda (b) (cdr (assoc '?a b)))
                                   (force-ll (prolog `(member (?a ?b ,"shelf") ((1 2 "shelf") (3 4 "shelf")))
                                                     '((?b . 4)))))))
           (is (= 1 compiles))
           (is (null (force-ll (prolog `(member (?a ?b ,"table") ((1 2 "shelf") (3 4 "shelf")))))))
           (is (= 2 compiles))
           ;; facts that change between two equal queries
           (eval '(def-fact-group afresh-query-test (afresh-query-fact)
                   (<- (afresh-query-fact 1))))
           (is (equal '(1) (mapcar (lambda (b) (cdr (assoc '?x b)))
                                   (force-ll (prolog (list 'afresh-query-fact '?x))))))
           (eval '(def-fact-group afresh-query-test (afresh-query-fact)
                   (<- (afresh-query-fact 2))))
           (is (equal '(2) (mapcar (lambda (b) (cdr (assoc '?x b)))
                                   (force-ll (prolog (list 'afresh-query-fact '?x)))))))
      (sb-int:unencapsulate 'cram-prolog::compile-goal-term 'count)
      (ignore-errors (remove-fact-group 'afresh-query-test)))))

(test goals-compiled-once-when-asked-again
  "A goal object asked repeatedly (a constant query) is compiled once and kept; goals built
afresh for one query each are not kept; both give their solutions."
  (let ((constant (list 'member '?x '(a b c)))
        (before (hash-table-count cram-prolog::*compiled-goals*)))
    (dotimes (i 200)
      (let ((g (gensym)))
        (is (equal (list g 'b) (mapcar (lambda (b) (cdr (assoc '?x b)))
                                       (force-ll (prolog `(member ?x (,g b)))))))))
    (is (<= (hash-table-count cram-prolog::*compiled-goals*) before))
    (is (equal '(a b c) (mapcar (lambda (b) (cdr (assoc '?x b))) (force-ll (prolog constant)))))
    (is (equal '(a b c) (mapcar (lambda (b) (cdr (assoc '?x b))) (force-ll (prolog constant)))))
    (is (gethash constant cram-prolog::*compiled-goals*))))
