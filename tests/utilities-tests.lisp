;;;; Tests of CUT: lazy lists and bindings.

(defpackage :cram-utilities-tests
  (:use :cl :fiveam :cut))

(in-package :cram-utilities-tests)

(def-suite utilities :in cram-plans-tests:all :description "Lazy lists and bindings (CUT).")
(in-suite utilities)

(defun counting-naturals ()
  "An infinite lazy list of naturals and a function returning how often the generator ran."
  (let ((calls 0))
    (values (lazy-list ((i 0)) (incf calls) (cont i (1+ i)))
            (lambda () calls))))

(test lazy-list-is-lazy
  (multiple-value-bind (l calls) (counting-naturals)
    (is (= 1 (funcall calls)) "only the first element is computed at construction")
    (is (= 0 (lazy-car l)))
    (is (= 1 (funcall calls)))
    (is (= 3 (lazy-elt l 3)))
    (is (= 4 (funcall calls)))))

(test lazy-list-memoises
  (multiple-value-bind (l calls) (counting-naturals)
    (lazy-elt l 10)
    (let ((before (funcall calls)))
      (is (= 10 (lazy-elt l 10)))
      (is (= 5 (lazy-elt l 5)))
      (is (= before (funcall calls)) "re-reading does not call the generator again")
      (is (eq (lazy-cdr l) (lazy-cdr l)) "the expanded conses are shared"))))

(test lazy-take-of-infinite
  (multiple-value-bind (l calls) (counting-naturals)
    (let ((taken (lazy-take 5 l)))
      (is (equal '(0 1 2 3 4) (force-ll taken)))
      (is (<= (funcall calls) 5) "take 5 computes no more than 5 elements"))))

(test lazy-take-zero-and-short
  (is (null (force-ll (lazy-take 0 '(1 2 3)))))
  (is (equal '(1 2) (force-ll (lazy-take 5 '(1 2))))))

(test force-ll-expands-everything
  (let ((l (lazy-list ((i 0)) (if (< i 4) (cont (* i i) (1+ i)) (finish)))))
    (is (= 1 (expanded-length l)))
    (is (equal '(0 1 4 9) (force-ll l)))
    (is (= 4 (expanded-length l)))
    (is (equal '(0 1 4 9) l) "a forced lazy list is an ordinary list")))

(test lazy-list-next-and-finish-value
  (let ((odd (lazy-list ((i 0)) (cond ((> i 7) (finish :end)) ((oddp i) (cont i (1+ i))) (t (next (1+ i)))))))
    (is (equal '(1 3 5 7 :end) (force-ll odd)))))

(test empty-lazy-list-is-nil
  (is (null (lazy-list () (finish)))))

(test lazy-mapcar-and-filter
  (multiple-value-bind (l calls) (counting-naturals)
    (let ((squares (lazy-mapcar (lambda (x) (* x x)) l))
          (evens (lazy-filter #'evenp l)))
      (is (equal '(0 1 4 9) (force-ll (lazy-take 4 squares))))
      (is (equal '(0 2 4 6) (force-ll (lazy-take 4 evens))))
      (is (< (funcall calls) 10))))
  (is (equal '(11 22) (force-ll (lazy-mapcar #'+ '(1 2 3) '(10 20))))))

(test lazy-mapcan-and-append
  (is (equal '(1 1 2 2 3 3) (force-ll (lazy-mapcan (lambda (x) (list x x)) '(1 2 3)))))
  (is (equal '(1 3) (force-ll (lazy-mapcan (lambda (x) (and (oddp x) (list x))) '(1 2 3)))))
  (multiple-value-bind (l calls) (counting-naturals)
    (let ((app (lazy-append '(a b) l)))
      (is (equal '(a b 0 1) (force-ll (lazy-take 4 app))))
      (is (<= (funcall calls) 3)))))

(test lazy-fold-and-dolist
  (is (= 10 (lazy-fold #'+ '(1 2 3 4))))
  (is (= 20 (lazy-fold #'+ '(1 2 3 4) :initial-value 10)))
  (let ((seen '()))
    (lazy-dolist (x (lazy-take 3 (counting-naturals))) (push x seen))
    (is (equal '(2 1 0) seen))))

(test lazy-elt-past-end
  (is (null (lazy-elt '(1 2) 5))))

(test is-var-recognises-variables
  (is-true (is-var '?x))
  (is-true (is-var '?_))
  (is-false (is-var 'x))
  (is-false (is-var nil))
  (is-false (is-var "?x"))
  (is-true (is-anonymous-var '?_)))

(test var-value-follows-chains
  (let ((b '((?x . ?y) (?y . (1 ?z)) (?z . 3))))
    (is (equal '(1 3) (var-value '?x b)))
    (is (eq '?w (var-value '?w b)))
    (is-true (is-bound '?x b))
    (is-false (is-bound '?w b))))

(test unify-and-add-bdg
  (multiple-value-bind (b ok) (unify '(?a (2 ?b) . ?rest) '(1 (2 3) 4 5))
    (is-true ok)
    (is (= 1 (var-value '?a b)))
    (is (= 3 (var-value '?b b)))
    (is (equal '(4 5) (var-value '?rest b))))
  (is-false (nth-value 1 (unify '(?a ?a) '(1 2))))
  (is-true (nth-value 1 (unify '(?_ ?_) '(1 2))))
  (is-true (nth-value 1 (unify "str" "str")))
  (is-false (nth-value 1 (add-bdg '?x 2 '((?x . 1)))))
  (is (equal '((?x . 1)) (add-bdg '?x 1 '((?x . 1))))))

(test ground-and-vars-in
  (is-true (is-ground '(1 (2 ?x)) '((?x . a))))
  (is-false (is-ground '(1 (2 ?x))))
  (is (equal '(?a ?b) (vars-in '(f ?a (g ?b ?a) ?_)))))

(test with-vars-bound-macros
  ;; FiveAM's IS treats ?-symbols as its own pattern variables: compare outside IS.
  (let ((values (with-vars-bound (?x ?y) '((?x . 1)) (list ?x ?y))))
    (is (equal '(1 ?y) values)))
  (signals unbound-variable-error
    (with-vars-strictly-bound (?y) '((?x . 1)) ?y))
  (let ((x (with-vars-strictly-bound (?x) '((?x . 1)) ?x)))
    (is (= 1 x))))

(test rename-vars-is-consistent
  (let ((r (rename-vars '(?a ?b ?a))))
    (is (eq (first r) (third r)))
    (is (not (eq (first r) '?a)))
    (is-true (is-var (second r)))))
