;;;; Tests that the RETE API runs on an alpha/beta network: the work of a change, the sharing of
;;;; alpha memories and join nodes, the removal of tokens on retraction, and CRAM's documented
;;;; behaviours (handlers that change the working memory, Prolog patterns, nested patterns).

(in-package :cram-prolog-rete-tests)

(in-suite prolog-rete)

(defun stat (key)
  "The network statistic KEY (see CRAM-PROLOG::RETE-STATISTICS)."
  (getf (cram-prolog::rete-statistics) key))

(defun stat-delta (key function)
  "How much the statistic KEY grows while FUNCTION runs."
  (let ((before (stat key)))
    (funcall function)
    (- (stat key) before)))

(defun root-token-children ()
  "The number of tokens directly below the beta network's root token."
  (let ((root-token (first (cram-prolog::rset-items
                            (cram-prolog::beta-node-memory cram-prolog::*beta-root*)))))
    (let ((children (cram-prolog::token-children root-token)))
      (if children (cram-prolog::rset-count children) 0))))

(defmacro recording ((var) &body body)
  "Evaluate BODY with VAR bound to a function that records its arguments; returns the records,
oldest first."
  (let ((records (gensym "RECORDS")))
    `(let ((,records '()))
       (flet ((,var (&rest args) (push args ,records)))
         (declare (ignorable (function ,var)))
         ,@body)
       (reverse ,records))))

(test one-assertion-does-work-in-proportion-to-its-matches
  (with-clean-memory
    (with-productions ((chain (on ?a ?b) (on ?b ?c)))
      (let ((events '()))
        (with-production-handlers
            ((chain (op &key ?a ?b ?c) (push (list op ?a ?b ?c) events)))
          ;; 1000 facts the new ones do not join with, and 1000 of another functor.
          (dotimes (i 1000)
            (rete-assert (list 'on i (+ 100000 i)))
            (rete-assert (list 'color i 'red)))
          (is (null events))
          (is (<= (stat-delta :join-attempts (lambda () (rete-assert '(on 7777777 8888888)))) 2)
              "a fact that joins with nothing")
          (is (<= (stat-delta :join-attempts (lambda () (rete-assert '(on 100005 top)))) 3)
              "a fact that joins with one of the 1000")
          (is (equal '((:assert 5 100005 top)) events))
          ;; 50 facts (on j hub), then (on hub top): 50 joins made, 50 attempts (+1 at the top).
          (dotimes (j 50) (rete-assert (list 'on (list 'block j) 'hub)))
          (setf events '())
          (is (= 51 (stat-delta :join-attempts (lambda () (rete-assert '(on hub top))))))
          (is (= 50 (length events)))
          (is (every (lambda (e) (eq :assert (first e))) events)))))))

(test productions-with-the-same-pattern-shape-share-an-alpha-memory
  (with-clean-memory
    (let ((memories (stat :alpha-memories)))
      (with-productions ((on-any (on ?a ?b))
                         (red-on (on ?x ?y) (color ?x red))
                         (red (color ?c red))
                         (same (?op ?v ?v)))
        (let ((seen (recording (note)
                      (with-production-handlers ((on-any (&rest r) (apply #'note 'on-any r))
                                                 (red-on (&rest r) (apply #'note 'red-on r))
                                                 (red (&rest r) (apply #'note 'red r))
                                                 (same (&rest r) (apply #'note 'same r)))
                        (is (= (+ memories 3) (stat :alpha-memories))
                            "(on ?0 ?1), (color ?0 red) and (?0 ?1 ?1)")
                        (is (= 1 (stat-delta :alpha-items (lambda () (rete-assert '(on a b)))))
                            "one fact, one alpha memory, for two productions")
                        (is (= 2 (stat-delta :alpha-items (lambda () (rete-assert '(on c c))))))
                        (is (= 0 (stat-delta :alpha-items (lambda () (rete-assert '(weather sunny)))))
                            "a fact no pattern fits reaches no memory")
                        (is (= 1 (stat-delta :alpha-items (lambda () (rete-assert '(color a red))))))
                        (is (= 0 (stat-delta :alpha-items
                                             (lambda () (rete-assert '(color a blue))))))))))
          (is (= 5 (length seen)))
          (is (null (set-exclusive-or '((on-any :assert :?a a :?b b)
                                        (on-any :assert :?a c :?b c) (same :assert :?op on :?v c)
                                        (red-on :assert :?x a :?y b) (red :assert :?c a))
                                      seen :test #'equal)))))
      (is (= memories (stat :alpha-memories)) "the memories go with the productions"))))

(test productions-with-a-common-start-share-join-nodes
  (with-clean-memory
    (let ((nodes (stat :beta-nodes)))
      (with-productions ((p1 (on ?a ?b) (on ?b ?c))
                         (p2 (on ?a ?b) (color ?b red))
                         (p3 (on ?x ?y)))
        (with-production-handlers ((p1 (&rest r) r) (p2 (&rest r) r))
          (is (= (+ nodes 5) (stat :beta-nodes)) "3 join nodes and 2 production nodes")
          (with-production-handlers ((p3 (&rest r) r))
            (is (= (+ nodes 7) (stat :beta-nodes)) "P3 names its variables differently")
            (rete-assert '(on a b))
            (is (= 3 (stat :tokens)) "a token in each top join and in P3's production node")))
        (is (= nodes (stat :beta-nodes)))))))

(test retracting-removes-every-token
  (with-clean-memory
    (let ((asserted 0) (retracted 0) (before (cram-prolog::rete-statistics)))
      (with-production-handlers
          ((rete-test-stacked (op &key &allow-other-keys)
             (if (eq op :assert) (incf asserted) (incf retracted))))
        (dotimes (i 10000) (rete-assert (list 'on i (1+ i))))
        (is (= 9999 asserted))
        (is (= (+ 10000 9999 9999) (stat :tokens)))
        (is (= 10000 (root-token-children)))
        (dotimes (i 10000) (rete-retract (list 'on i (1+ i))))
        (is (= 9999 retracted))
        (is (= 0 (alpha-network-size)))
        (is (= 0 (stat :alpha-items)))
        (is (= 0 (stat :tokens)))
        (is (= 0 (root-token-children)))
        (is (= 0 (stat :index-buckets)))
        (is (= 0 (stat :left-index-buckets))))
      (let ((after (cram-prolog::rete-statistics)))
        (dolist (key '(:alpha-memories :alpha-nodes :beta-nodes))
          (is (= (getf before key) (getf after key)) "~s back to ~d" key (getf before key)))))))

(defvar *pairs* '() "The calls of RETE-TEST-NOTE-PAIR, newest first.")

(defun rete-test-note-pair (op &key ?x ?z &allow-other-keys)
  "A handler named by a symbol, for PAIRS-OF-ONE-MEMORY-ARE-EACH-MATCHED-ONCE."
  (push (list op ?x ?z) *pairs*))

(test pairs-of-one-memory-are-each-matched-once
  ;; Both patterns read the same alpha memory: a new fact enters both joins, and must be joined
  ;; with itself and with every older fact once.
  (with-clean-memory
    (with-productions ((pairs (on ?x ?y) (on ?z ?w))
                       (self-on (on ?a ?a)))
      (let ((*pairs* '()) (loops '()))
        (with-production-handlers ((self-on (op &key ?a) (push (list op ?a) loops)))
          (register-production-handler 'pairs 'rete-test-note-pair)
          (rete-assert '(on a a))
          (is (equal '((:assert a a)) *pairs*))
          (rete-assert '(on b c))
          (is (= 4 (length *pairs*)))
          (is (null (set-exclusive-or '((:assert a a) (:assert a b) (:assert b a) (:assert b b))
                                      *pairs* :test #'equal)))
          (is (equal '((:assert a)) loops))
          (rete-retract '(on a a))
          (is (= 3 (count :retract *pairs* :key #'first)))
          (is (equal '((:retract a) (:assert a)) loops))
          (remove-production-handler 'pairs 'rete-test-note-pair)
          (signals prolog-error (register-production-handler 'pairs 'rete-test-no-such-function)))))))

(test a-fact-is-asserted-once-and-retracting-an-unknown-fact-does-nothing
  (with-clean-memory
    (let ((events (recording (note)
                    (with-production-handlers ((rete-test-stacked (&rest r) (apply #'note r)))
                      (rete-assert '(on a b))
                      (rete-assert '(on b c))
                      (rete-assert (list 'on 'b 'c))
                      (is (= 2 (alpha-network-size)))
                      (is (equal '(on x y) (rete-retract '(on x y))))
                      (rete-retract '(on b c))
                      (rete-retract '(on b c))
                      (is (= 1 (alpha-network-size)))))))
      (is (equal '((:assert :?a a :?b b :?c c) (:retract :?a a :?b b :?c c)) events)))))

(test asserted-facts-are-copied
  (with-clean-memory
    (let ((fact (list 'on 'a 'b)))
      (rete-assert fact)
      (setf (third fact) 'z)
      (is (equal '(((?x . b))) (rete-prove '((on a ?x)))))
      (rete-retract '(on a b))
      (is (= 0 (alpha-network-size))))))

(test handlers-may-assert-and-retract-facts
  ;; CRAM's example in productions.lisp: a handler that makes ON transitive.
  (with-clean-memory
    (with-productions ((stacked (on ?a ?b) (on ?b ?c)))
      (with-production-handlers
          ((stacked (op &key ?a ?c &allow-other-keys)
             (ecase op
               (:assert (rete-assert `(on ,?a ,?c)))
               (:retract (rete-retract `(on ,?a ,?c))))))
        (rete-assert '(on a b))
        (rete-assert '(on b c))
        (rete-assert '(on c d))
        (is (= 6 (alpha-network-size)))
        (is (equal '(b c d) (mapcar (lambda (b) (cdr (assoc '?x b))) (rete-prove '((on a ?x))))))
        (rete-retract '(on c d))
        (is (equal '(b c) (mapcar (lambda (b) (cdr (assoc '?x b))) (rete-prove '((on a ?x))))))
        (is (= 3 (alpha-network-size)))))))

(test a-failing-handler-leaves-the-network-consistent
  (with-clean-memory
    (let ((late '()))
      (with-productions ((pair (on ?a ?b) (on ?b ?c)))
        (with-production-handlers
            ((pair (op &key &allow-other-keys)
               (when (eq op :assert) (error "handler failed"))))
          (rete-assert '(on a b))
          (signals error (rete-assert '(on b c)))
          (is (= 2 (alpha-network-size)))
          (with-production-handlers
              ((pair (op &key ?a ?c &allow-other-keys) (push (list op ?a ?c) late)))
            (is (equal '((:assert a c)) late) "the match was made before the handler failed")
            (rete-retract '(on a b))
            (is (equal '(:retract a c) (first late)))))))))

(test productions-with-prolog-patterns
  (with-clean-memory
    (with-productions ((on-tray (on ?a ?b) (member ?b (tray table)))
                       (listed (member ?x (cup plate)) (on ?x ?y)))
      (let ((events
              (recording (note)
                (with-production-handlers
                    ((on-tray (op &key ?a ?b) (note 'on-tray op ?a ?b))
                     (listed (op &key ?x ?y) (note 'listed op ?x ?y)))
                  (rete-assert '(on cup tray))
                  (rete-assert '(on cup plate))
                  (rete-assert '(on fork table))
                  (rete-retract '(on cup tray))))))
        (is (equal '((on-tray :assert cup tray) (listed :assert cup tray)
                     (listed :assert cup plate)
                     (on-tray :assert fork table)
                     (on-tray :retract cup tray) (listed :retract cup tray))
                   ;; the order of two productions' events of one change is not specified
                   (let ((first-two (subseq events 0 2)) (last-two (subseq events 4 6)))
                     (append (sort (copy-list first-two) #'string> :key (lambda (e) (symbol-name (first e))))
                             (subseq events 2 4)
                             (sort (copy-list last-two) #'string> :key (lambda (e) (symbol-name (first e))))))))
        (is (equal '(((?y . table)))
                   (rete-prove '((on fork ?y) (member ?y (tray table))))))))))

(test nested-patterns-repeated-and-segment-variables
  (with-clean-memory
    (with-productions ((placed (pose ?o (?x ?y)))
                       (in-kitchen (at ?o (room kitchen)))
                       (route (route ?start !?_ ?end)))
      (let ((events
              (recording (note)
                (with-production-handlers
                    ((placed (op &key ?o ?x ?y) (note 'placed op ?o ?x ?y))
                     (in-kitchen (op &key ?o) (note 'in-kitchen op ?o))
                     (route (op &key ?start ?end) (note 'route op ?start ?end)))
                  (rete-assert '(pose cup (1 2)))
                  (rete-assert '(pose cup (1 2 3)))
                  (rete-assert '(pose cup 5))
                  (rete-assert '(at cup (room kitchen)))
                  (rete-assert '(at cup (room hall)))
                  (rete-assert '(route a b c d))
                  (rete-assert '(route a))))))
        (is (equal '((placed :assert cup 1 2) (in-kitchen :assert cup) (route :assert a d))
                   events))))))

(test productions-are-dropped-with-their-networks
  (with-clean-memory
    (let ((nodes (stat :beta-nodes)) (memories (stat :alpha-memories)) (calls 0))
      (register-production 'rete-test-redefined '((lamp ?l on)))
      (register-production-handler 'rete-test-redefined (lambda (&rest r) (declare (ignore r))
                                                          (incf calls)))
      (rete-assert '(lamp l1 on))
      (is (= 1 calls))
      (is (< nodes (stat :beta-nodes)))
      (register-production 'rete-test-redefined '((lamp ?l off)))
      (is (= nodes (stat :beta-nodes)) "redefinition drops the network and the handlers")
      (is (= memories (stat :alpha-memories)))
      (rete-assert '(lamp l2 on))
      (is (= 1 calls))
      (register-production-handler 'rete-test-redefined (lambda (&rest r) (declare (ignore r))
                                                          (incf calls)))
      (is (remove-production 'rete-test-redefined))
      (is (= nodes (stat :beta-nodes)))
      (is (not (remove-production 'rete-test-redefined)))
      ;; WITH-PRODUCTIONS takes its productions' networks along, handlers or not.
      (with-productions ((rete-test-scoped (lamp ?l on)))
        (register-production-handler 'rete-test-scoped (lambda (&rest r) r))
        (is (< nodes (stat :beta-nodes))))
      (is (= nodes (stat :beta-nodes)))
      (is (= memories (stat :alpha-memories))))))

(test clearing-the-working-memory-calls-no-handler
  (with-clean-memory
    (let ((events (recording (note)
                    (with-production-handlers ((rete-test-stacked (&rest r) (apply #'note r)))
                      (rete-assert '(on a b))
                      (rete-assert '(on b c))
                      (clear-alpha-network)
                      (is (= 0 (stat :tokens)))
                      (is (= 0 (stat :alpha-items)))
                      (rete-assert '(on a b))
                      (rete-assert '(on b c))))))
      (is (equal '((:assert :?a a :?b b :?c c) (:assert :?a a :?b b :?c c)) events)))))

(test clearing-keeps-the-matches-of-prolog-patterns
  (with-clean-memory
    (with-productions ((listed (member ?x (cup)) (on ?x ?y)))
      (let ((events (recording (note)
                      (with-production-handlers ((listed (op &key ?x ?y) (note op ?x ?y)))
                        (rete-assert '(on cup tray))
                        (clear-alpha-network)
                        (is (= 1 (stat :tokens)) "the token of (member cup (cup)) stays")
                        (rete-assert '(on cup shelf))))))
        (is (equal '((:assert cup tray) (:assert cup shelf)) events))))))

(test the-network-serves-several-threads
  (with-clean-memory
    (let ((asserted 0) (retracted 0))
      (with-production-handlers
          ((rete-test-stacked (op &key &allow-other-keys)
             (if (eq op :assert) (incf asserted) (incf retracted))))
        (let ((threads
                (loop for k below 4
                      collect (let ((k k))
                                (sb-thread:make-thread
                                 (lambda ()
                                   (dotimes (i 300)
                                     (rete-assert (list 'on (list k i) (list k (1+ i)))))
                                   (dotimes (i 300)
                                     (rete-retract (list 'on (list k i) (list k (1+ i)))))))))))
          (mapc #'sb-thread:join-thread threads))
        (is (= (* 4 299) asserted))
        (is (= (* 4 299) retracted))
        (is (= 0 (stat :tokens)))
        (is (= 0 (alpha-network-size)))))))

(test rete-prove-reads-alpha-memories
  (with-clean-memory
    (with-productions ((on-any (on ?a ?b)))
      (with-production-handlers ((on-any (&rest r) r))
        (dotimes (i 1000) (rete-assert (list 'color i 'red)))
        (rete-assert '(on a b))
        (rete-assert '(on a c))
        (let (solutions)
          (is (= 2 (stat-delta :prove-attempts
                               (lambda () (setf solutions (rete-prove '((on a ?x))))))))
          (is (equal '(((?x . b)) ((?x . c))) solutions)))
        (is (= 1002 (stat-delta :prove-attempts (lambda () (rete-prove '((size ?x ?y))))))
            "a pattern no alpha memory holds is matched against every fact")
        (let ((solution (first (rete-prove '((on ?x ?y)) '((?x . a))))))
          (is (eq 'a (cdr (assoc '?x solution))))
          (is (eq 'b (cdr (assoc '?y solution)))))
        (is (equal '(((?c . red))) (rete-prove '((color 5 ?c)))))))))

(test bad-productions-and-patterns-are-named-in-errors
  (flet ((message (thunk)
           (handler-case (progn (funcall thunk) nil)
             (prolog-error (e) (princ-to-string e)))))
    (let ((m (message (lambda () (register-production 'rete-test-bad '((on (a . !?rest))))))))
      (is (search "!?REST" m))
      (is (search "(ON (A . !?REST))" m)))
    (is (search "\"name\"" (message (lambda () (register-production "name" '((on ?a)))))))
    (is (search "(ON ?A)" (message (lambda () (register-production 'rete-test-bad '(on ?a))))))
    (is (search "!?X" (message (lambda () (rete-prove '((on a . !?x)))))))
    (is (search "RETE-TEST-MISSING"
                (message (lambda () (register-production-handler 'rete-test-missing #'list)))))
    (is (search "42" (message (lambda () (rete-retract 42)))))
    (is (not (gethash 'rete-test-bad cram-prolog::*productions*)))))
