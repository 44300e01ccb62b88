;;;; CRAM's RETE API: a working memory of facts, productions (conjunctions of patterns) and
;;;; handlers called when a production starts or stops to hold. The facts pass through a RETE
;;;; network (rete-alpha.lisp, rete-beta.lisp): a change of the working memory costs work in
;;;; proportion to the partial matches it makes or breaks, never a new match from scratch.
;;;;
;;;; A production's network exists while the production has handlers: it is built (and filled
;;;; from the working memory) when the first handler is registered and removed with the last one.

(in-package :cram-prolog)

(defvar *productions* (make-hash-table :test 'eq) "Production name → PRODUCTION.")

(defun alpha-network-size ()
  "The number of facts in the working memory."
  (hash-table-count *working-memory*))

(defun clear-alpha-network ()
  "Remove every fact from the working memory (no handler is called) and forget the matches of the
productions; the productions and their handlers stay."
  (with-network-change (clear-alpha-network)
    (let ((*silent* t))
      (loop for wme being the hash-values of *working-memory*
            do (network-retract wme)))
    (clrhash *working-memory*))
  t)

(defun rete-assert (fact)
  "Add FACT (a list; a copy is kept) to the working memory; the productions it completes call
their handlers with :ASSERT. A fact already there (EQUAL) is not added again. Returns FACT."
  (check-fact fact 'rete-assert)
  (with-network-change (rete-assert)
    (unless (gethash fact *working-memory*)
      (let* ((copy (copy-tree fact))
             (wme (make-wme copy (incf *next-wme-serial*))))
        (setf (gethash copy *working-memory*) wme)
        (network-assert wme))))
  fact)

(defun rete-retract (fact)
  "Remove FACT from the working memory; the productions that held through it call their handlers
with :RETRACT. A fact not in the working memory is ignored. Returns FACT."
  (check-fact fact 'rete-retract)
  (with-network-change (rete-retract)
    (let ((wme (gethash fact *working-memory*)))
      (when wme
        (remhash fact *working-memory*)
        (network-retract wme))))
  fact)

(defmacro with-facts-asserted ((&rest facts) &body body)
  "Evaluate BODY with the FACTS (evaluated) asserted into the working memory; they are
retracted when BODY is left."
  (let ((list (gensym "FACTS")))
    `(let ((,list (list ,@facts)))
       (unwind-protect
            (progn (mapc #'rete-assert ,list) ,@body)
         (mapc #'rete-retract ,list)))))

;;; One-shot queries

(defun prove-conjunction (patterns bindings)
  "Every extension of BINDINGS under which the conjunction PATTERNS holds: fact patterns are
matched against the facts of the smallest alpha memory holding their matches (else against the
whole working memory), Prolog patterns are proved."
  (if (null patterns)
      (list bindings)
      (let ((pattern (first patterns)))
        (if (prolog-pattern-p pattern)
            (loop for solution in (force-ll (prolog pattern bindings))
                  append (prove-conjunction (rest patterns) (append solution bindings)))
            (let ((query (substitute-vars pattern bindings)))
              (loop for wme in (candidate-wmes query)
                    append (multiple-value-bind (new ok)
                               (progn (incf *prove-attempts*)
                                      (match-term query (wme-fact wme) '()))
                             (when ok
                               (prove-conjunction (rest patterns) (append new bindings))))))))))

(defun rete-prove (patterns &optional bindings)
  "The solutions (a list of binding alists for the variables of PATTERNS) of the conjunction
PATTERNS against the working memory, extending BINDINGS (patterns of Prolog predicates are
proved by Prolog). Solutions come in the order the facts were asserted, without duplicates."
  (unless (and (listp patterns) (every #'consp patterns))
    (prolog-error "RETE-PROVE: ~s is not a list of patterns." patterns))
  (dolist (pattern patterns) (check-pattern pattern 'rete-prove))
  (with-rete-lock ()
    (remove-duplicates
     (loop for b in (prove-conjunction patterns bindings)
           collect (filter-bindings patterns b bindings))
     :test #'equal :from-end t)))

(def-prolog-handler rete-holds (bindings ?fact)
  (with-rete-lock ()
    (check-pattern ?fact 'rete-holds)
    (loop for wme in (candidate-wmes ?fact)
          for (b ok) = (multiple-value-list
                        (progn (incf *prove-attempts*) (match-term ?fact (wme-fact wme) bindings)))
          when ok collect b)))

(defvar *object-ids* (make-hash-table :test 'eq :weakness :key :synchronized t)
  "Object → its number (OBJECT-ID).")
(defvar *next-object-id* 0)

(defun object-id (object)
  "A number that stays the same for OBJECT (compared with EQ) while it lives, for facts about
objects."
  (or (gethash object *object-ids*)
      (with-rete-lock ()
        (or (gethash object *object-ids*)
            (setf (gethash object *object-ids*) (incf *next-object-id*))))))

;;; Productions

(defun check-production (name patterns function)
  "Signal a PROLOG-ERROR naming FUNCTION unless NAME is a symbol and PATTERNS a non-empty list
of patterns."
  (unless (and name (symbolp name))
    (prolog-error "~s: the name ~s is not a symbol." function name))
  (unless (and (consp patterns) (alexandria:proper-list-p patterns)
               (every (lambda (p) (and (consp p) (alexandria:proper-list-p p))) patterns))
    (prolog-error "~s ~s: ~s is not a non-empty list of patterns." function name patterns))
  (dolist (pattern patterns) (check-pattern pattern function name)))

(defun drop-production-network (production)
  "Remove PRODUCTION's nodes (and the nodes and memories only it used); no handler is called."
  (let ((node (production-node production)))
    (when node
      (setf (production-node production) nil)
      (remove-beta-node node))))

(defun forget-production (production)
  "Drop PRODUCTION's handlers and network."
  (setf (production-handlers production) '())
  (drop-production-network production))

(defun register-production (name patterns)
  "Define (or redefine) the production NAME as the conjunction of PATTERNS. A redefined
production loses its handlers and its matches (no handler is called)."
  (check-production name patterns 'register-production)
  (with-network-change (register-production)
    (let ((old (gethash name *productions*)))
      (when old (forget-production old)))
    (setf (gethash name *productions*) (make-production name patterns)))
  name)

(defmacro def-production (name &body patterns)
  "Define the production NAME: the conjunction of PATTERNS (not evaluated)."
  `(register-production ',name ',patterns))

(defun find-production (name function)
  "The production NAME, or a PROLOG-ERROR naming FUNCTION."
  (or (gethash name *productions*)
      (prolog-error "~s: there is no production named ~s." function name)))

(defun remove-production (name)
  "Forget the production NAME with its handlers and matches (no handler is called). True when
it existed."
  (with-network-change (remove-production)
    (let ((production (gethash name *productions*)))
      (when production
        (remhash name *productions*)
        (forget-production production)
        t))))

(defun clear-productions ()
  "Forget every production (no handler is called)."
  (with-network-change (clear-productions)
    (loop for production being the hash-values of *productions*
          do (forget-production production))
    (clrhash *productions*))
  t)

(defun call-with-productions (specs function)
  "Call FUNCTION with the productions SPECS ((name pattern...) ...) defined, shadowing those of
the same names; afterwards they are gone (their networks too) and the shadowed ones are back."
  (let ((*productions* (with-rete-lock () (alexandria:copy-hash-table *productions*)))
        (made '()))
    (unwind-protect
         (progn
           (loop for (name . patterns) in specs
                 do (check-production name patterns 'with-productions)
                    (let ((production (make-production name patterns)))
                      (push production made)
                      (with-rete-lock () (setf (gethash name *productions*) production))))
           (funcall function))
      (when made
        (with-network-change (with-productions)
          (mapc #'forget-production made))))))

(defmacro with-productions ((&rest productions) &body body)
  "Evaluate BODY with PRODUCTIONS ((name pattern...) ...) defined (shadowing productions of
those names); afterwards the productions are as before."
  `(call-with-productions ',productions (lambda () ,@body)))

(defun register-production-handler (name handler)
  "Call HANDLER, a function (or the name of one) of (operation &key ?var... &allow-other-keys),
with :ASSERT whenever the production NAME starts to hold for some values of its variables and
with :RETRACT when it stops to; the matches that hold when it is registered are reported with
:ASSERT at once. Handlers run after the change that triggered them is complete, holding the
network's lock; they may assert and retract facts."
  (unless (or (functionp handler) (and handler (symbolp handler) (fboundp handler)))
    (prolog-error "REGISTER-PRODUCTION-HANDLER: ~s is not a function." handler))
  (with-rete-lock ()
    (let ((production nil) (report '()))
      (with-network-change (register-production-handler)
        (setf production (find-production name 'register-production-handler))
        (cond ((member handler (production-handlers production)))
              ((production-node production)
               (push handler (production-handlers production))
               (setf report (mapcar #'token-bindings
                                    (rset-items (beta-node-memory
                                                 (production-node production))))))
              (t
               (setf (production-node production) (build-production-network production))
               (push handler (production-handlers production)))))
      (dolist (bindings report)
        (apply handler :assert (production-handler-arguments production bindings)))
      name)))

(defun remove-production-handler (name handler)
  "Stop calling HANDLER for the production NAME; without handlers, the production's network is
removed."
  (with-network-change (remove-production-handler)
    (let ((production (find-production name 'remove-production-handler)))
      (setf (production-handlers production) (remove handler (production-handlers production)))
      (unless (production-handlers production)
        (drop-production-network production))
      name)))

(defmacro with-production-handlers ((&rest handlers) &body body)
  "Evaluate BODY with HANDLERS ((production-name lambda-list form...) ...) registered (see
REGISTER-PRODUCTION-HANDLER); they are removed when BODY is left."
  (let ((names (loop for h in handlers collect (gensym (format nil "~a-HANDLER" (first h))))))
    `(let ,(loop for (nil lambda-list . forms) in handlers for n in names
                 collect `(,n (lambda ,lambda-list ,@forms)))
       (unwind-protect
            (progn ,@(loop for h in handlers for n in names
                           collect `(register-production-handler ',(first h) ,n))
                   ,@body)
         ,@(loop for h in handlers for n in names
                 collect `(remove-production-handler ',(first h) ,n))))))

(defun rete-statistics ()
  "A plist describing the network: :FACTS, :ALPHA-MEMORIES, :ALPHA-NODES (of the discrimination
tree), :ALPHA-ITEMS (facts held by alpha memories), :INDEX-BUCKETS (of the alpha indexes),
:BETA-NODES, :TOKENS, :LEFT-INDEX-BUCKETS, :JOIN-ATTEMPTS and :PROVE-ATTEMPTS (counters)."
  (with-rete-lock ()
    (let ((beta-nodes 0) (tokens 0) (left-buckets 0))
      (map-beta-nodes (lambda (node)
                        (incf beta-nodes)
                        (incf tokens (rset-count (beta-node-memory node)))
                        (when (and (join-node-p node) (join-node-left-index node))
                          (incf left-buckets (hash-table-count (join-node-left-index node))))))
      (list :facts (hash-table-count *working-memory*)
            :alpha-memories (hash-table-count *alpha-memories*)
            :alpha-nodes (alpha-tree-size)
            :alpha-items (loop for m being the hash-values of *alpha-memories*
                               sum (rset-count (alpha-memory-items m)))
            :index-buckets (loop for m being the hash-values of *alpha-memories*
                                 sum (loop for index in (alpha-memory-indexes m)
                                           sum (hash-table-count (alpha-index-buckets index))))
            :beta-nodes beta-nodes
            :tokens tokens
            :left-index-buckets left-buckets
            :join-attempts *join-attempts*
            :prove-attempts *prove-attempts*))))

(setf (documentation 'rete-holds 'function)
      "Prolog predicate (rete-holds ?fact): ?fact matches a fact of the working memory, one solution
per fact, in the order of assertion.")
