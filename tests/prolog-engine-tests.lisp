;;;; Tests of the fact engine's extension interfaces and of corner cases of the solver.

(in-package :cram-prolog-tests)

(in-suite prolog)

(def-native-predicate between-native (m cont low high value)
  ;; a native predicate with several solutions, one per backtracking step
  (let ((lo (deref-term low)) (hi (deref-term high)) (v (deref-term value)))
    (if (integerp v)
        (when (<= lo v hi) (solve-continue cont))
        (unify-each m value (loop for i from lo to hi collect i) cont))))

(test native-predicates
  (is (equal '(nil) (all '(between-native 1 5 3))))
  (is (null (all '(between-native 1 5 7))))
  (is (equal '(1 2 3 4 5) (values-of '?v '(between-native 1 5 ?v))))
  (is (equal '(3) (values-of '?v '(once (between-native 1 5 ?v) (> ?v 2)))))
  (is (null (all '(between-native 1 5))) "a goal of another length fails"))

(def-prolog-handler lazy-numbers (bindings ?n)
  (let ((i 0))
    (lazy-list ()
      (incf *handler-calls*)
      (cont (add-bdg ?n (incf i) bindings)))))

(test handler-solutions-are-taken-lazily
  (setf *handler-calls* 0)
  (let ((result (prolog '(lazy-numbers ?n))))
    (is (= 1 (var-value '?n (lazy-car result))))
    (is (= 1 *handler-calls*) "an infinite handler only computes what is read")
    (is (= 3 (var-value '?n (lazy-elt result 2))))
    (is (= 3 *handler-calls*))))

(test removing-a-handler
  (eval '(def-prolog-handler temporary-handler (bindings ?x) (list (add-bdg ?x 1 bindings))))
  (is (equal '(1) (values-of '?x '(temporary-handler ?x))))
  (is (remove-prolog-handler 'temporary-handler))
  (is (null (handler-bind ((warning #'muffle-warning)) (all '(temporary-handler ?x))))))

(def-fact-group cut-branches ()
  (<- (cut-in-then ?x) (-> (true) (and (member ?x (1 2)) (cut)) (fail)))
  (<- (cut-in-then 3))
  (<- (cut-in-condition ?x) (-> (and (member ?y (1 2)) (cut)) (member ?x (a b))))
  (<- (cut-in-condition c)))

(test cut-in-if-then-else
  (is (equal '(1) (values-of '?x '(cut-in-then ?x))) "a cut in the then branch cuts the clause")
  (is (equal '(a b c) (values-of '?x '(cut-in-condition ?x)))
      "a cut in the condition is local to it"))

(test nested-collection
  (is (equal '(((1 2) (3)))
             (values-of '?all '(findall ?l (or (findall ?x (member ?x (1 2)) ?l) (== ?l (3))) ?all))))
  (is (equal '(nil) (all '(every (fail) (== ?r 1)))) "EVERY over no solutions succeeds")
  (is (equal '(2) (values-of '?n '(and (findall ?x (member ?x (a b)) ?l) (length ?l ?n))))))

(def-fact-group mixed-index ()
  (<- (mixed a 1)) (<- (mixed ?_ 2)) (<- (mixed b 3)) (<- (mixed a 4)) (<- (mixed (c) 5))
  (<- (mixed "s" 6)) (<- (mixed 7 7)) (<- (mixed ?_ 8)) (<- (mixed a 9)) (<- (mixed (d) 10)))

(test index-keeps-clause-order
  (is (equal '(1 2 4 8 9) (values-of '?n '(mixed a ?n))))
  (is (equal '(2 3 8) (values-of '?n '(mixed b ?n))))
  (is (equal '(2 5 8 10) (values-of '?n '(mixed (?_) ?n))) "compound first arguments")
  (is (equal '(2 6 8) (values-of '?n '(mixed "s" ?n))))
  (is (equal '(2 7 8) (values-of '?n '(mixed 7 ?n))))
  (is (equal '(1 2 3 4 5 6 7 8 9 10) (values-of '?n '(mixed ?_ ?n)))))

(test database-changes-while-querying
  (let* ((stop nil)
         (writer (sb-thread:make-thread
                  (lambda ()
                    (loop for i from 0 below 200 until stop
                          do (eval `(def-fact-group churning () (<- (churn ,i)))))
                    t)))
         (ok (loop repeat 200
                   always (let ((v (handler-bind ((warning #'muffle-warning))
                                     (values-of '?x '(churn ?x)))))
                            (and (<= (length v) 1) (every #'integerp v))))))
    (setf stop t)
    (is-true (sb-thread:join-thread writer))
    (is-true ok "every query sees one consistent definition")))

(test query-errors
  (signals prolog-error (prolog 42))
  (signals prolog-error (prolog '(length ?l ?n)))
  (signals prolog-error (prolog '(take -1 (a) ?x)))
  (signals prolog-error (prolog '(true) 'not-an-alist)))

(test queries-are-reusable
  (let ((goal '(member ?x (1 2 3))))
    (is (equal '(1 2 3) (values-of '?x goal)))
    (is (equal '(1 2 3) (values-of '?x goal)) "the same goal object gives the same answers")
    (is (equal '(2) (values-of '?x goal '((?x . 2))))))
  (let ((result (prolog '(member ?x (a b)))))
    (is (equal (force-ll result) (force-ll result)) "a forced answer list stays the same")))

(test strict-reading-of-answers
  (let ((b (lazy-car (prolog '(== ?x 5)))))
    (is (= 5 (with-vars-strictly-bound (?x) b ?x))))
  (signals unbound-variable-error
    (with-vars-strictly-bound (?y) (lazy-car (prolog '(== ?x 5))) ?y)))

(test clause-with-many-variables
  (eval '(def-fact-group wide ()
          (<- (wide ?a ?b ?c ?d ?e ?f ?g ?h ?i ?j)
            (== (?a ?b ?c ?d ?e) (1 2 3 4 5))
            (== (?f ?g ?h ?i ?j) (?a ?b ?c ?d ?e)))))
  (is (equal '((1 2 3 4 5 1 2 3 4 5))
             (mapcar (lambda (b) (mapcar (lambda (v) (var-value v b))
                                         '(?1 ?2 ?3 ?4 ?5 ?6 ?7 ?8 ?9 ?10)))
                     (all '(wide ?1 ?2 ?3 ?4 ?5 ?6 ?7 ?8 ?9 ?10))))))

(test built-ins-are-documented
  (dolist (functor '(and or not -> *-> once call cut true fail bound ground == equal < > <= >=
                     member append length sort findall bagof setof forall every take lisp-fun
                     lisp-pred symbol-value set-symbol-value slot-value get-slot-value
                     instance-of lisp-type format))
    (is (stringp (documentation functor 'predicate)) "~s has documentation" functor)))
