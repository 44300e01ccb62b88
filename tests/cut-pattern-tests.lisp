;;;; Tests of CUT's pattern matcher, segment variables in UNIFY, delayed values, the lazy-list
;;;; behaviours CRAM documents, threads and REPLACE-ALL.

(defpackage :cram-utilities-pattern-tests
  (:use :cl :fiveam :cut))

(in-package :cram-utilities-pattern-tests)

(def-suite cut-patterns :in cram-plans-tests:all
  :description "CUT: PAT-MATCH, segment variables, DELAY/FORCE, lazy-list edges, threads.")
(in-suite cut-patterns)

(defun match (pattern sequence)
  (multiple-value-list (pat-match pattern sequence)))

(test variable-kinds
  (is-true (is-var '?x))
  (is-true (is-var :?x))
  (is-false (is-var '!?x))
  (is-true (is-segvar '!?rest))
  (is-false (is-segvar '?rest))
  (is-false (is-segvar '(!?x)))
  (is-true (is-segform '(!?x a)))
  (is-false (is-segform '!?x))
  (is-false (is-segform '(?x !?y)))
  (is-true (is-unnamed-var '?_))
  (is-false (is-unnamed-var '!?_))
  (is (eq '?x (var-name '?x)))
  (is (eq '?tail (var-name '!?tail)))
  (is-true (is-unnamed-var (var-name '!?_)))
  (signals simple-error (var-name 'plain))
  (signals simple-error (var-name '(?x))))

(test gen-var-makes-fresh-uninterned-variables
  (let ((vars (loop repeat 50 collect (gen-var "?G-"))))
    (is (every #'is-var vars))
    (is (every #'is-genvar vars))
    (is (= 50 (length (remove-duplicates vars))))
    (is (string= "?G-" (subseq (symbol-name (first vars)) 0 3))))
  (is-false (is-genvar '?interned))
  (signals error (gen-var "NO-QUESTION-MARK"))
  (signals error (is-genvar 42)))

(test pat-match-constants-and-variables
  (is (equal '(nil t) (match '(a b c) '(a b c))))
  (is (equal '(nil nil) (match '(a b) '(a b c))))
  (is (equal '(nil nil) (match '(a ?x) '(b c))))
  (is (bindings-equal '((?x . a) (?y . (1 2))) (pat-match '(?x b ?y) '(a b (1 2)))))
  (is (eq 'foo (var-value '?x (pat-match '(?x ?x) '(foo foo)))))
  (is (equal '(nil nil) (match '(?x ?x) '(nil foo))))
  (is (equal '(nil t) (match '(?_ ?_) '(1 2))))
  (is-true (pat-match-p '(1 ?x) '(1 2)))
  (is-false (pat-match-p '(1 ?x) '(2 2)))
  (is-true (pat-match-p '("a" ?x) '("a" 1) nil :test #'equal))
  (is-false (pat-match-p '("a" ?x) (list (copy-seq "a") 1))))

(test pat-match-segment-variables
  (is (equal '(b c) (var-value '?x (pat-match '(a !?x d) '(a b c d)))))
  (let ((b (pat-match '(k !?x k !?y !?z end) '(k k 1 2 end))))
    (is (null (var-value '?x b)))
    (is (null (var-value '?y b)))
    (is (equal '(1 2) (var-value '?z b))))
  (let ((b (pat-match '(!?front ?last) '(1 2 3))))
    (is (equal '(1 2) (var-value '?front b)))
    (is (eql 3 (var-value '?last b))))
  (is (equal '(p q) (var-value '?x (pat-match '(!?x ?x) '(p q (p q))))))
  (is (equal '(nil nil) (match '(!?x end) '(a b c))))
  (is (equal '(nil nil) (match '(!?x) 'atom)))
  (is (equal '(nil nil) (match '(a !?x) '(a b . dotted))))
  (is (equal '(nil nil) (match '(?x !?x) '(1 1)))))

(test pat-match-errors
  (signals simple-error (pat-match '(a ?x) '(a ?y)))
  (signals simple-error (pat-match '(a b) '(!?y)))
  (signals simple-error (pat-match '!?alone 'x))
  (signals simple-error (pat-match '(a . !?x) '(a . b))))

(test with-pat-vars-bound-binds-lisp-variables
  (is (equal '(1 (2 3) 4)
             (with-pat-vars-bound (?a !?mid ?z) '(1 2 3 4) (list ?a ?mid ?z))))
  (signals simple-error (with-pat-vars-bound (?a b) '(1 c) ?a))
  (signals warning (with-pat-vars-bound (a b) '(a b) t)))

(test bindings-equal-and-patterns-eq
  (is-true (bindings-equal '((?a . 1) (?b . (2))) '((?b . (2)) (?a . 1))))
  (is-false (bindings-equal '((?a . 1)) '((?a . 2))))
  (is-true (bindings-equal '((?a . 1)) '((?a . 1.0)) :test #'=))
  (is-true (patterns-eq '(f ?x (g ?y)) '(f ?a (g ?b))))
  (is-false (patterns-eq '(f ?x) '(f a))))

(test var-value-and-is-bound-of-non-variables
  (let ((b '((?x . (a ?y)) (?y . 1))))
    (is (equal '(?x ?y) (var-value '(?x ?y) b)) "a list is returned as it is")
    (is (equal '(a 1) (var-value '?x b)))
    (is (eql 7 (var-value 7 b)))
    (is-true (is-bound '(?unbound) b))
    (is-true (is-bound 'atom b))
    (is-false (is-bound '?unbound b))
    (is-true (is-bound '?y b))))

(test unify-with-segment-variables
  (is (equal '(b c) (var-value '?x (unify '(a !?x d) '(a b c d)))))
  (let ((b (unify '(!?x ?y) '(a b c))))
    (is (equal '(a b) (var-value '?x b)))
    (is (eq 'c (var-value '?y b))))
  (is (equal '(a b) (var-value '?x (unify '(a b (a b)) '(!?x ?x)))) "on the right too")
  (is-false (nth-value 1 (unify '(!?x d) '(a b c))))
  (is-false (nth-value 1 (unify '(a !?x) '(a b . c))))
  (signals simple-error (unify '!?foo 'bar))
  (signals simple-error (unify 'bar '!?foo))
  (signals simple-error (unify '(a . !?x) '(a . b))))

(test map-tree-maps-atoms
  (is (equal '(2 (3 . 4) 5) (map-tree #'1+ '(1 (2 . 3) 4)))))

(test delay-computes-once-on-force
  (let* ((runs 0)
         (d (delay (incf runs) :value)))
    (is-true (delay-p d))
    (is (= 0 runs))
    (is (eq :value (force d)))
    (is (eq :value (force d)))
    (is (= 1 runs))
    (is (eql 5 (force 5)) "a value that is not delayed is its own value")
    (is-false (delay-p 5))))

(test lazy-list-body-returning-ends-the-list
  (let ((runs 0))
    (let ((l (lazy-list ((i 0)) (when (< i 3) (incf runs) (cont i (1+ i))))))
      (is (= 1 runs))
      (is (equal '(0 1 2) (force-ll l)))
      (is (= 3 runs))))
  (is (null (lazy-list () nil))))

(test lazy-mapcan-signals-simple-error-for-non-lists
  (is (equal '(1 2 3) (force-ll (lazy-mapcan #'identity '((1) nil (2) nil (3))))))
  (is (equal '(1 a 2 b) (force-ll (lazy-mapcan #'list '(1 2 3) '(a b)))))
  (let ((l (lazy-mapcan #'identity '((1) 2 3))))
    (is (eql 1 (lazy-car l)))
    (signals simple-error (lazy-cdr l))
    (signals lazy-list-type-error (force-ll (lazy-mapcan #'identity '(oops))))))

(defvar *level* :outer)

(test lazy-lists-keep-their-dynamic-environment
  (let ((l (with-lazy-list-dynamic-environment ((*level* :inner))
             (lazy-list ((i 3)) (when (> i 0) (cont *level* (1- i)))))))
    (is (eq :outer *level*))
    (is (equal '(:inner :inner :inner) (force-ll l))))
  (let ((plain (lazy-list ((i 2)) (when (> i 0) (cont *level* (1- i))))))
    (let ((*level* :rebound))
      (is (equal '(:outer :rebound) (force-ll plain))))))

(test lazy-skip-flatten-rests
  (is (equal '(3 4) (force-ll (lazy-skip 2 '(1 2 3 4)))))
  (is (null (lazy-skip 9 '(1 2))))
  (is (equal '(1 2 3 4) (force-ll (lazy-flatten '(1 (2 (3)) 4)))))
  (is (equal '((1 2) (2)) (force-ll (lazy-rests '(1 2))))))

(test threads-spawn-and-join
  (let ((threads (spawn-threads 3 "worker" (lambda () (* 6 7)))))
    (is (= 3 (length threads)))
    (is (equal '("worker-1" "worker-2" "worker-3") (mapcar #'sb-thread:thread-name threads)))
    (is (equal '(42 42 42) (mapcar #'join-thread threads))))
  (let ((slow (spawn-thread "slow" #'sleep 5)))
    (is (eq :late (join-thread slow :timeout 0.05 :on-timeout :late)))
    (is-true (kill-thread slow))
    (is (eq :failed (join-thread slow :on-failure :failed))))
  (is (eq (current-thread) sb-thread:*current-thread*))
  (signals error (join-thread (current-thread)))
  (signals error (join-thread :not-a-thread)))

(test replace-all-replaces-every-occurrence
  (is (string= "a-b-c" (replace-all "a::b::c" "::" "-")))
  (is (string= "XX" (replace-all "aaaa" "aa" "X")))
  (is (string= "same" (replace-all "same" "zz" "y")))
  (signals error (replace-all "abc" "" "x"))
  (signals error (replace-all 'abc "a" "x")))
