;;;; Tests of Prolog API that CRAM exports besides PROLOG itself: FILTER-BINDINGS, UNIFY and
;;;; UNIFY-P with segment variables, and CRAM's rule for extending another group's functor.

(defpackage :cram-prolog-api-tests
  (:use :cl :fiveam :cram-prolog)
  (:shadowing-import-from :fiveam #:fail))

(in-package :cram-prolog-api-tests)

(def-suite prolog-api :in cram-plans-tests:all
  :description "FILTER-BINDINGS, UNIFY, extension of fact groups.")
(in-suite prolog-api)

(test filter-bindings-keeps-the-form-variables
  (let ((all '((?x . 1) (?helper . 2) (?y . (a ?helper)))))
    (is (cut:bindings-equal '((?x . 1)) (filter-bindings '(foo ?x) all)))
    (is (= 1 (length (filter-bindings '(foo ?x) all))))
    (is (equal '(a 2) (cut:var-value '?y (filter-bindings '(bar ?y) all))))
    (is (null (filter-bindings '(baz ?unknown) all)))))

(test filter-bindings-extends-the-initial-bindings
  ;; ?x is bound to ?y initially; the query bound ?y, so ?x gets its value through ?y
  (let* ((initial '((?x . ?y)))
         (solution (first (prolog '(member ?y (7 8)) initial)))
         (filtered (filter-bindings '(foo ?x) (append solution initial) initial)))
    (is (= 7 (cut:var-value '?x filtered)))
    (is (eq '?y (cdr (assoc '?x filtered))) "the initial binding itself is kept"))
  (signals prolog-error (filter-bindings '(foo ?x) 42))
  (signals prolog-error (filter-bindings '(foo ?x) nil '(oops))))

(test unify-is-prologs-and-handles-segment-variables
  (is (eq 'unify (find-symbol "UNIFY" :cram-prolog)))
  (is (eq 'cut:unify 'prolog:unify))
  (is (eq 'cut:?_ 'prolog:?_))
  (is-true (unify-p '(a ?x) '(a 1)))
  (is-false (unify-p '(a ?x ?x) '(a 1 2)))
  (multiple-value-bind (bindings ok) (unify '(?head !?tail) '(1 2 3))
    (is-true ok)
    (is (eql 1 (cut:var-value '?head bindings)))
    (is (equal '(2 3) (cut:var-value '?tail bindings))))
  (is (equal '(((?none)) t) (multiple-value-list (unify '(foo !?none) '(foo)))))
  (signals simple-error (unify '(a . !?x) '(a b))))

(defun drop-groups (&rest names)
  (mapc #'remove-fact-group names))

(test undeclared-extension-of-another-groups-functor-is-an-error
  (unwind-protect
       (progn
         (eval '(def-fact-group api-test-owner (api-test-color)
                 (<- (api-test-color red))))
         ;; the owner lists the functor, but the extending group does not: CRAM's error
         (signals fact-group-error
           (eval '(def-fact-group api-test-intruder ()
                   (<- (api-test-color blue)))))
         (is (equal '((?c . red)) (first (prolog '(api-test-color ?c)))))
         (is (= 1 (length (cut:force-ll (prolog '(api-test-color ?c))))))
         ;; declared in the extending group: accepted, and the clauses follow the owner's
         (eval '(def-fact-group api-test-friend (api-test-color)
                 (<- (api-test-color green))))
         (is (equal '(red green)
                    (mapcar (lambda (b) (cut:var-value '?c b))
                            (cut:force-ll (prolog '(api-test-color ?c))))))
         ;; redefining the owner keeps its right to the functor
         (eval '(def-fact-group api-test-owner ()
                 (<- (api-test-color crimson))))
         (is (equal '(crimson green)
                    (mapcar (lambda (b) (cut:var-value '?c b))
                            (cut:force-ll (prolog '(api-test-color ?c)))))))
    (drop-groups 'api-test-owner 'api-test-intruder 'api-test-friend)))

(test extension-error-names-both-groups-and-the-functor
  (unwind-protect
       (progn
         (eval '(def-fact-group api-test-first ()
                 (<- (api-test-size big))))
         (let ((message (handler-case (progn (eval '(def-fact-group api-test-second ()
                                                     (<- (api-test-size small))))
                                             "")
                          (fact-group-error (e) (princ-to-string e)))))
           (is (search "API-TEST-SECOND" message))
           (is (search "API-TEST-FIRST" message))
           (is (search "API-TEST-SIZE" message))))
    (drop-groups 'api-test-first 'api-test-second)))

(test the-default-heap-limit-follows-the-running-dynamic-space
  (is (eq :default *prolog-heap-limit*))
  (is (= (floor (sb-ext:dynamic-space-size) 3) (cram-prolog::heap-limit)))
  (let ((*prolog-heap-limit* 12345678))
    (is (= 12345678 (cram-prolog::heap-limit))))
  (let ((*prolog-heap-limit* nil))
    (is (null (cram-prolog::heap-limit)))
    (is (not (null (prolog '(member ?x (1 2)))))))
  (let ((*prolog-heap-limit* "lots"))
    (let ((e (handler-case (progn (cut:force-ll (prolog '(member ?x (1 2)))) nil)
               (prolog-error (c) c))))
      (is (typep e 'prolog-error))
      (is (search "\"lots\"" (princ-to-string e)))
      (is (search "*PROLOG-HEAP-LIMIT*" (princ-to-string e))))))
