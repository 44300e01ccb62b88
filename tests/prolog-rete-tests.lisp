;;;; Tests of the RETE API: working memory, productions and their handlers, RETE-PROVE.

(defpackage :cram-prolog-rete-tests
  (:use :cl :fiveam :cram-prolog)
  (:shadowing-import-from :fiveam #:fail))

(in-package :cram-prolog-rete-tests)

(def-suite prolog-rete :in cram-plans-tests:all
  :description "RETE-ASSERT, productions, handlers, RETE-PROVE.")
(in-suite prolog-rete)

(defmacro with-clean-memory (&body body)
  `(unwind-protect (progn (clear-alpha-network) ,@body)
     (clear-alpha-network)))

(def-production rete-test-stacked
  (on ?a ?b)
  (on ?b ?c))

(test handlers-see-productions-start-and-stop-holding
  (with-clean-memory
    (let ((events '()))
      (with-production-handlers
          ((rete-test-stacked (operation &key ?a ?b ?c)
             (push (list operation ?a ?b ?c) events)))
        (rete-assert '(on cup plate))
        (is (null events) "one fact is no stack")
        (rete-assert '(on plate tray))
        (is (equal '((:assert cup plate tray)) events))
        (rete-assert '(on tray table))
        (is (equal '(:assert plate tray table) (first events)))
        (rete-retract '(on plate tray))
        (is (= 4 (length events)))
        (is (equal '((:retract cup plate tray) (:retract plate tray table))
                   (sort (subseq events 0 2) #'string< :key (lambda (e) (symbol-name (second e))))))
        (is (= 2 (alpha-network-size))))
      (rete-assert '(on plate tray))
      (is (= 4 (length events)) "no handler after WITH-PRODUCTION-HANDLERS"))))

(test with-productions-and-with-facts-asserted
  (with-clean-memory
    (let ((triggered '()))
      (with-productions ((rete-test-identity (?op ?x ?x)))
        (with-production-handlers
            ((rete-test-identity (operation &key ?x &allow-other-keys)
               (push (list operation ?x) triggered)))
          (with-facts-asserted ('(same 1 1) '(same 1 2))
            (is (= 2 (alpha-network-size))))
          (is (= 0 (alpha-network-size)) "retracted when the body is left")))
      (is (equal '((:retract 1) (:assert 1)) triggered))
      (signals prolog-error (register-production-handler 'rete-test-identity (lambda (&rest r) r)))
      (signals prolog-error (register-production-handler 'rete-test-stacked 42)))))

(test handlers-registered-late-see-what-already-holds
  (with-clean-memory
    (rete-assert '(on a b))
    (rete-assert '(on b c))
    (let ((seen '()))
      (with-production-handlers
          ((rete-test-stacked (operation &key ?a &allow-other-keys)
             (push (list operation ?a) seen)))
        (is (equal '((:assert a)) seen))))))

(test rete-prove-and-rete-holds
  (with-clean-memory
    (rete-assert '(on a b))
    (rete-assert '(on b c))
    (rete-assert '(on b d))
    (is (equal '(((?x . b))) (rete-prove '((on a ?x) (on ?x c)))))
    (is (null (rete-prove '((on a ?x) (on ?x e)))))
    (is (equal '((?y . c) (?y . d))
               (mapcar (lambda (b) (assoc '?y b)) (rete-prove '((on a ?x) (on ?x ?y))))))
    (is (equal '(c d) (sort (mapcar (lambda (b) (cut:var-value '?y b))
                                    (cut:force-ll (prolog '(rete-holds (on b ?y)))))
                            #'string<)))
    (signals prolog-error (rete-assert 'not-a-list))
    (signals prolog-error (rete-prove 'not-patterns))))

(test object-ids-are-stable
  (let ((a (list 1)) (b (list 1)))
    (is (= (object-id a) (object-id a)))
    (is (/= (object-id a) (object-id b)))))
