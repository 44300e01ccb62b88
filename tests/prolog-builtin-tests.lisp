;;;; Tests of the fact engine's built-in predicates, Lisp handlers, laziness, threads and limits.

(in-package :cram-prolog-tests)

(in-suite prolog)

;;; Comparison and tests

(test bound-and-ground
  (is (equal '(1) (values-of '?x '(and (== ?x 1) (bound ?x)))))
  (is (null (all '(bound ?x))))
  (is (null (all '(and (== ?x ?y) (bound ?x)))) "bound to an unbound variable is not bound")
  (is (equal '(2) (values-of '?x '(and (== ?x ?y) (== ?y 2) (bound ?x)))) "through a variable chain")
  (is (equal '(nil) (all '(ground (a (1 2) "s")))))
  (is (null (all '(ground (a ?x)))))
  (is (equal '(3) (values-of '?x '(and (== ?x 3) (ground (a ?x)))))))

(test equality-predicates
  (is (equal '(((?x . 5))) (all '(== ?x 5))) "== unifies")
  (is (equal '(((?x . 1) (?y . 2))) (all '(== (?x 2) (1 ?y)))))
  (is (equal '(nil) (all '(equal (1 "a") (1 "a")))))
  (is (null (all '(equal ?x 1))) "EQUAL does not bind")
  (is (equal '(1) (values-of '?x '(and (== ?x 1) (equal ?x 1))))))

(test numeric-comparison
  (is (equal '(nil) (all '(< 1 2))))
  (is (null (all '(< 2 1))))
  (is (equal '(nil) (all '(> 2.5 1))))
  (is (equal '(nil) (all '(<= 2 2))))
  (is (equal '(nil) (all '(>= 3 2))))
  (is (null (all '(>= 1 2))))
  (is (equal '(2 3) (values-of '?x '(and (member ?x (1 2 3)) (> ?x 1)))))
  ;; a comparison of something that is not a number is a clear error, not a silent failure
  (let ((*break-on-lisp-errors* nil))
    (signals prolog-error (all '(< a 1)))
    (signals prolog-error (all '(> ?x 1)))))

;;; Lists

(test member-predicate
  (is (equal '(a b c) (values-of '?x '(member ?x (a b c)))))
  (is (equal '(nil) (all '(member b (a b c)))))
  (is (equal '(nil nil) (all '(member b (b b)))) "one solution per occurrence")
  (is (null (all '(member z (a b)))))
  (is (equal '(2) (values-of '?y '(member (1 ?y) ((0 1) (1 2) (3 4)))))))

(test member-on-lazy-lists
  (let* ((produced 0)
         (naturals (lazy-list ((i 0)) (incf produced) (cont i (1+ i)))))
    (is (equal '(0) (values-of '?x '(once (member ?x ?l)) `((?l . ,naturals)))))
    (is (= 1 (length (all '(once (member 7 ?l)) `((?l . ,naturals)))))
        "finds an element of an infinite list")
    (is (= 8 produced) "computes only as far as needed")))

(test append-predicate
  (is (equal '((1 2 3 4)) (values-of '?l '(append (1 2) (3 4) ?l))))
  (is (equal '(() (1) (1 2)) (values-of '?a '(append ?a ?b (1 2)))))
  (is (equal '((2)) (values-of '?b '(append (1) ?b (1 2))))))

(test length-predicate
  (is (equal '(3) (values-of '?n '(length (a b c) ?n))))
  (is (equal '(0) (values-of '?n '(length () ?n))))
  (is (equal '(nil) (all '(length (a b) 2))))
  (is (equal '(2) (mapcar #'length (values-of '?l '(length ?l 2)))) "makes a list of fresh variables")
  (let ((l (lazy-list ((i 0)) (if (< i 4) (cont i (1+ i)) (finish)))))
    (is (equal '(4) (values-of '?n '(length ?l ?n) `((?l . ,l)))) "forces a finite lazy list")))

(test sort-predicate
  (is (equal '((1 2 3)) (values-of '?s '(sort (3 1 2) < ?s))))
  (is (equal '((3 2 1)) (values-of '?s '(sort (3 1 2) > ?s))))
  (is (equal '((1 2.5 "a" b)) (values-of '?s '(sort (b "a" 2.5 1) ?s))) "standard order")
  (signals prolog-error (all '(sort (3 1) no-such-function-anywhere ?s))))

(test take-subset-reduce-max-string-concat
  (is (equal '((a b)) (values-of '?t '(take 2 (a b c) ?t))))
  (is (equal '((a b c)) (values-of '?t '(take 5 (a b c) ?t))))
  (is (equal '(nil) (all '(subset (a c) (a b c)))))
  (is (null (all '(subset (a d) (a b c)))))
  (is (equal '(6) (values-of '?r '(reduce + (1 2 3) ?r))))
  (is (equal '(7) (values-of '?r '(max (3 7 5) ?r))))
  (is (equal '(4) (values-of '?r '(max 4 2 ?r))))
  (is (equal '("ab-c") (values-of '?r '(string-concat ("ab" "-" "c") ?r))))
  (is (equal '("xy") (values-of '?r '(string-concat "x" "y" ?r)))))

;;; Calling Lisp

(test lisp-fun-and-lisp-pred
  (is (equal '(3) (values-of '?z '(lisp-fun + 1 2 ?z))))
  (is (equal '(6) (values-of '?z '(and (== ?a 2) (lisp-fun * ?a 3 ?z)))))
  (is (equal '(nil) (all '(lisp-pred evenp 4))))
  (is (null (all '(lisp-pred evenp 3))))
  (is (equal '(nil) (all `(lisp-pred ,(lambda (x) (eq x 'a)) a))) "a function object")
  (is (is-var (first (values-of '?r '(lisp-fun identity ?v ?r))))
      "an unbound variable reaches Lisp as a ?symbol"))

(test break-on-lisp-errors
  (let ((*break-on-lisp-errors* nil) (warned nil))
    (handler-bind ((warning (lambda (w) (setf warned t) (muffle-warning w))))
      (is (null (all '(lisp-fun car 5 ?x))))
      (is (null (all '(lisp-pred car 5)))))
    (is-true warned))
  (let ((*break-on-lisp-errors* t))
    (signals type-error (all '(lisp-fun car 5 ?x)))
    (signals type-error (all '(lisp-pred car 5)))))

(defvar *prolog-test-value* 10)

(test symbol-values
  (let ((*prolog-test-value* 10))
    (is (equal '(10) (values-of '?v '(symbol-value *prolog-test-value* ?v))))
    (is (equal '(nil) (all '(set-symbol-value *prolog-test-value* 42))))
    (is (= 42 *prolog-test-value*)))
  (signals prolog-error (all '(symbol-value "not a symbol" ?v))))

(defclass probe () ((size :initarg :size :initform 1 :accessor probe-size)))

(test slots-and-instances
  (let ((p (make-instance 'probe :size 3)))
    (is (equal '(3) (values-of '?s `(slot-value ,p size ?s))))
    (is (equal '(3) (values-of '?s `(get-slot-value ,p size ?s))))
    (is (equal '(nil) (all `(slot-value ,p size 9))))
    (is (= 9 (probe-size p)) "SLOT-VALUE writes a bound value")
    (is (equal '(probe) (values-of '?type `(instance-of ?type ,p))))
    (is (equal '(nil) (all `(instance-of probe ,p))))
    (is (equal '(nil) (all `(lisp-type ,p probe)))))
  (let ((made (var-value '?o (car (all '(instance-of probe ?o))))))
    (is (typep made 'probe))
    (is (= 1 (probe-size made)))))

(test output-predicates
  (is (equal "x=3" (with-output-to-string (*standard-output*)
                     (all '(format "x=~a" 3)))))
  (signals warning (all '(warn "careful: ~a" 1)))
  (signals error (all '(error "stop: ~a" 2))))

;;; Handlers

(defvar *handler-calls* 0)

(def-prolog-handler three-colours (bindings ?colour)
  (incf *handler-calls*)
  (if (is-var ?colour)
      (lazy-list ((colours '(red green blue)))
        (if colours
            (cont (add-bdg ?colour (car colours) bindings) (cdr colours))
            (finish)))
      (when (member ?colour '(red green blue))
        (list bindings))))

(test handler-solutions
  (is (equal '(red green blue) (values-of '?c '(three-colours ?c))))
  (is (equal '(nil) (all '(three-colours green))))
  (is (null (all '(three-colours pink))))
  (is (equal '(green) (values-of '?c '(and (three-colours ?c) (== ?c green)))))
  (is (equal '((red green blue)) (values-of '?l '(findall ?c (three-colours ?c) ?l)))))

(def-prolog-handler with-fallback (bindings ?x)
  (when (eq ?x :from-handler) (list bindings)))

(def-fact-group fallback-clauses (with-fallback)
  (<- (with-fallback :from-clauses)))

(test handler-and-clauses
  (is (equal '(nil) (all '(with-fallback :from-handler))))
  (is (equal '(nil) (all '(with-fallback :from-clauses)))
      "clauses are tried when the handler gives no solution")
  (is (null (all '(with-fallback :nothing))))
  (is (equal '(:from-clauses) (values-of '?x '(with-fallback ?x)))))

(def-prolog-handler pair-up (bindings ?a ?b)
  (multiple-value-bind (new ok) (add-bdg ?b (list ?a '?fresh) bindings)
    (when ok (list new))))

(test handler-binding-shapes
  (let ((b (car (all '(pair-up 1 ?p)))))
    (is (= 1 (first (var-value '?p b))))
    (is (is-var (second (var-value '?p b))) "a new variable from a handler stays a variable"))
  (is (equal '(nil) (all '(pair-up 1 (1 2)) )) "binds the handler's ?symbols back")
  (is (null (all '(pair-up 1 (2 ?x))))))

;;; Laziness

(defvar *side-effects* 0)
(defun count-call (x) (incf *side-effects*) x)

(def-fact-group counted ()
  (<- (counted ?y) (member ?x (1 2 3)) (lisp-fun count-call ?x ?y)))

(test laziness-of-solutions
  (setf *side-effects* 0)
  (let ((result (prolog '(counted ?y))))
    (is (= 1 *side-effects*) "the first solution calls the counter once")
    (is (= 1 (var-value '?y (lazy-car result))))
    (is (= 1 *side-effects*))
    (lazy-cdr result)
    (is (= 2 *side-effects*))
    (force-ll result)
    (is (= 3 *side-effects*))))

(def-fact-group naturals ()
  (<- (natural 0))
  (<- (natural ?n) (natural ?m) (lisp-fun 1+ ?m ?n)))

(test infinite-generators-stay-lazy
  (let ((result (prolog '(natural ?n))))
    (is (= 0 (var-value '?n (lazy-car result))))
    (is (= 5 (var-value '?n (lazy-elt result 5)))))
  (is (equal '(0 1 2) (mapcar (lambda (b) (var-value '?n b))
                              (force-ll (lazy-take 3 (prolog '(natural ?n))))))))

;;; Indexing, recursion, threads

(defun make-many-objects (n)
  (eval `(def-fact-group many-objects ()
           (<- (many ?_ unknown))
           ,@(loop for i below n
                   collect `(<- (many ,(intern (format nil "OBJ-~d" i)) ,(if (evenp i) 'even 'odd))))
           (<- (many "string-key" string)))))

(test first-argument-index
  (make-many-objects 10000)
  (is (equal '(unknown odd) (values-of '?k '(many obj-501 ?k))))
  (is (equal '(unknown) (values-of '?k '(many :first-var-clause ?k)))
      "a clause with a variable first argument matches any key")
  (is (equal '(unknown even) (values-of '?k '(many ?x ?k) '((?x . obj-500)))))
  (is (equal '(unknown string) (values-of '?k '(many "string-key" ?k))))
  (is (equal '(unknown) (values-of '?k '(many no-such-object ?k))))
  (is (= 10002 (length (all '(many ?x ?k)))))
  (let ((start (get-internal-real-time)))
    (dotimes (i 1000) (prolog '(many obj-9999 ?k)))
    (is (< (- (get-internal-real-time) start) (* 2 internal-time-units-per-second))
        "an indexed lookup does not scan the clauses")))

(def-fact-group count-down ()
  (<- (count-down 0))
  (<- (count-down ?n) (> ?n 0) (lisp-fun 1- ?n ?m) (count-down ?m))
  (<- (list-length () 0))
  (<- (list-length (?_ . ?t) ?n) (list-length ?t ?m) (lisp-fun 1+ ?m ?n))
  (<- (nest 0 ?x ?x))
  (<- (nest ?n ?acc ?r) (lisp-fun 1- ?n ?m) (nest ?m (f ?acc) ?r)))

(test deep-recursion
  (is (equal '(nil) (all '(count-down 1000000))) "a million-step tail recursion")
  (is (equal '(100000) (values-of '?n '(list-length ?l ?n)
                                  `((?l . ,(make-list 100000 :initial-element 'x)))))
      "a deep non-tail recursion"))

(test resource-exhaustion-is-a-clean-error
  (signals prolog-resource-error (all '(nest 300000 a ?r)))
  (is (equal '(nil) (all '(count-down 10))) "the image keeps working"))

(test queries-from-several-threads
  (let* ((threads (loop for i below 4
                        collect (let ((i i))
                                  (sb-thread:make-thread
                                   (lambda ()
                                     (loop repeat 200
                                           always (and (equal (values-of '?s `(is-on-shelf cereal ?s))
                                                              '(shelf-one-level-4 shelf-two-level-3
                                                                shelf-one-level-2))
                                                       (equal (values-of '?n '(list-length (a b c) ?n))
                                                              '(3))
                                                       (equal (values-of '?x `(== ?x ,i)) (list i)))))))))
         (results (mapcar #'sb-thread:join-thread threads)))
    (is (every #'identity results))))

(test facts-added-at-run-time
  (remove-facts '(runtime-fact ?x))
  (add-fact '(runtime-fact 1))
  (add-fact '(runtime-fact 2))
  (is (equal '(1 2) (values-of '?x '(runtime-fact ?x))))
  (is (= 1 (remove-facts '(runtime-fact 1))))
  (is (equal '(2) (values-of '?x '(runtime-fact ?x))))
  (signals prolog-error (add-fact "not a fact")))

(test malformed-goals
  (signals prolog-error (all '(and 42)))
  (signals prolog-error (all '("string" 1)))
  (signals prolog-error (all '(-> (true) (true) (true) (true)))))
