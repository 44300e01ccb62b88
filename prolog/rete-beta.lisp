;;;; The beta network: for each production a chain of nodes below a root, one per pattern. A join
;;;; node joins the tokens (partial matches) of its parent with the facts of an alpha memory that
;;;; agree with them on the variables bound before; a Prolog node proves a Prolog pattern for
;;;; each token of its parent; a production node, the chain's end, holds the complete matches and
;;;; reports them to the production's handlers. Productions whose patterns start alike share the
;;;; nodes of that start.
;;;;
;;;; Tokens form a tree (each token has its parent's token as parent): retracting a fact deletes
;;;; the tokens made with it and everything below them, so nothing is matched again. A join node
;;;; whose pattern shares variables with the earlier patterns finds its partners through hash
;;;; indexes on both sides (ALPHA-INDEX, and its LEFT-INDEX of tokens), so an assertion costs
;;;; work in proportion to the tokens and facts that agree with it.
;;;;
;;;; Handlers are not called while a change propagates: the :ASSERT and :RETRACT events are
;;;; collected and delivered once the network is consistent again, so a handler may itself assert
;;;; or retract facts. A Prolog pattern is proved when a token reaches its node; later changes of
;;;; the Prolog database do not update the matches it gave.

(in-package :cram-prolog)

(defstruct (beta-node (:constructor nil) (:copier nil))
  "A node of the beta network: its PARENT node, its CHILDREN nodes and its MEMORY, the RSET of
the tokens it made."
  parent (children '()) (memory (make-rset)))

(defstruct (root-node (:include beta-node) (:constructor make-root-node ()) (:copier nil))
  "The top of the beta network; its memory holds one empty token.")

(defstruct (join-node (:include beta-node) (:constructor make-join-node (parent pattern amem))
                      (:copier nil))
  "Joins the parent's tokens with the facts of the alpha memory AMEM that fit PATTERN.
SEGMENTED: PATTERN holds segment variables and is matched with MATCH-TERM. HASH-VARS: PATTERN's
variables the earlier fact patterns bound; INDEX (on AMEM) and LEFT-INDEX (key → RSET of parent
tokens) hash both sides by their values. DYN-VARS and NEW-VARS, alists var → path: variables a
Prolog pattern may have bound, and variables bound here first."
  pattern amem segmented (hash-vars '()) (index nil) (left-index nil)
  (dyn-vars '()) (new-vars '()))

(defstruct (prolog-node (:include beta-node) (:constructor make-prolog-node (parent goal))
                        (:copier nil))
  "Proves GOAL for each token of its parent; one token per solution."
  goal)

(defstruct (production-node (:include beta-node)
                            (:constructor make-production-node (parent production))
                            (:copier nil))
  "The end of a PRODUCTION's chain: its tokens are the production's current matches."
  production)

(defstruct (token (:constructor make-token (parent wme bindings node)) (:copier nil))
  "A partial match: the PARENT token, the WME it added (NIL for Prolog and production nodes),
the BINDINGS so far (alist var → value), the NODE holding it (NIL once deleted) and its CHILDREN
(an RSET or NIL)."
  parent wme bindings node (children nil))

(defstruct (production (:constructor make-production
                           (name patterns
                            &aux (arguments
                                  (loop for var in (vars-in patterns)
                                        collect (cons (intern (symbol-name var) :keyword) var)))))
                       (:copier nil))
  "A production: NAME, its PATTERNS (terms whose ?variables are bound across them), its
HANDLERS, while it has handlers its production NODE, and the ARGUMENTS its handlers get (alist
keyword → variable)."
  name patterns (handlers '()) (node nil) (arguments '()))

(defun make-beta-root ()
  "A root node holding its empty token."
  (let ((root (make-root-node)))
    (rset-add (beta-node-memory root) (make-token nil nil '() root))
    root))

(defvar *beta-root* (make-beta-root) "The root of the beta network.")

;;; Changes and events

(defvar *rete-events* nil
  "While a change propagates: a cons whose car collects the events (production operation
bindings), newest first.")
(defvar *propagating* nil "True while a change of the network propagates.")
(defvar *silent* nil "True while tokens are dropped without telling handlers.")

(defun queue-event (production operation bindings)
  "Note that PRODUCTION started (:ASSERT) or stopped (:RETRACT) holding with BINDINGS."
  (unless *silent*
    (push (list production operation bindings) (car *rete-events*))))

(defun production-handler-arguments (production bindings)
  "The keyword arguments of a handler call: :?VAR value for each variable of PRODUCTION."
  (loop for (keyword . var) in (production-arguments production)
        append (list keyword (binding-value var bindings))))

(defun call-production-handlers (production operation bindings)
  "Call every handler of PRODUCTION with OPERATION and BINDINGS."
  (let ((arguments (production-handler-arguments production bindings)))
    (dolist (handler (production-handlers production))
      (apply handler operation arguments))))

(defun call-with-network-change (function name)
  "Call FUNCTION, which changes the network, holding the lock; then call the handlers of the
productions that started or stopped holding, in order. NAME is the operation, for the error
signalled when a change starts while another one propagates (from a Prolog pattern)."
  (with-rete-lock ()
    (when *propagating*
      (prolog-error "~s: the RETE network cannot change while another change propagates (a ~
                     Prolog pattern of a production changed it)." name))
    (let ((events (list '())))
      (multiple-value-prog1 (let ((*rete-events* events) (*propagating* t))
                              (funcall function))
        (loop for (production operation bindings) in (reverse (car events))
              do (call-production-handlers production operation bindings))))))

(defmacro with-network-change ((name) &body body)
  "Evaluate BODY as a change of the network named NAME (see CALL-WITH-NETWORK-CHANGE)."
  `(call-with-network-change (lambda () ,@body) ',name))

;;; Tokens

(defun add-token (node parent wme bindings)
  "Make NODE's token below PARENT for WME and BINDINGS and pass it on."
  (let ((token (make-token parent wme bindings node)))
    (rset-add (or (token-children parent) (setf (token-children parent) (make-rset))) token)
    (when wme (rset-add (wme-tokens wme) token))
    (rset-add (beta-node-memory node) token)
    (if (production-node-p node)
        (queue-event (production-node-production node) :assert bindings)
        (dolist (child (beta-node-children node))
          (left-activate child token)))
    token))

(defun token-key (join token)
  "The values of JOIN's hash variables in TOKEN."
  (let ((bindings (token-bindings token)))
    (mapcar (lambda (var) (binding-value var bindings)) (join-node-hash-vars join))))

(defun left-index-remove (join token)
  "Remove TOKEN from JOIN's left index."
  (let* ((key (token-key join token))
         (table (join-node-left-index join))
         (bucket (gethash key table)))
    (when (and bucket (rset-remove bucket token) (zerop (rset-count bucket)))
      (remhash key table))))

(defun delete-token (token from-parent)
  "Delete TOKEN and the tokens below it; a production's match reports :RETRACT. FROM-PARENT:
TOKEN's parent is being deleted too (it need not forget TOKEN)."
  (let ((node (token-node token)))
    (when node
      (let ((children (token-children token)))
        (when children
          (dolist (child (rset-items children))
            (delete-token child t))
          (setf (token-children token) nil)))
      (rset-remove (beta-node-memory node) token)
      (if (production-node-p node)
          (queue-event (production-node-production node) :retract (token-bindings token))
          (dolist (child (beta-node-children node))
            (when (and (join-node-p child) (join-node-left-index child))
              (left-index-remove child token))))
      (let ((wme (token-wme token)))
        (when wme (rset-remove (wme-tokens wme) token)))
      (unless from-parent
        (let ((siblings (token-children (token-parent token))))
          (when siblings (rset-remove siblings token))))
      (setf (token-node token) nil))))

;;; Activation

(defun join-bindings (join token wme)
  "TOKEN's bindings extended by the values JOIN's pattern takes from WME's fact, as (values
bindings t), or (values nil nil) when they disagree (the hash variables agree already)."
  (let ((fact (wme-fact wme))
        (bindings (token-bindings token)))
    (if (join-node-segmented join)
        (match-term (join-node-pattern join) fact bindings)
        (progn
          (loop for (var . path) in (join-node-dyn-vars join)
                do (let ((cell (assoc var bindings :test #'eq))
                         (value (value-at-path fact path)))
                     (cond ((or (null cell) (is-var (cdr cell)))
                            (push (cons var value) bindings))
                           ((not (equal (cdr cell) value))
                            (return-from join-bindings (values nil nil))))))
          (loop for (var . path) in (join-node-new-vars join)
                do (push (cons var (value-at-path fact path)) bindings))
          (values bindings t)))))

(defun join-attempt (join token wme)
  "Join TOKEN with WME at JOIN (counted in *JOIN-ATTEMPTS*)."
  (incf *join-attempts*)
  (multiple-value-bind (bindings ok) (join-bindings join token wme)
    (when ok (add-token join token wme bindings))))

(defun right-activate (join wme)
  "WME entered JOIN's alpha memory: join it with the parent's tokens that agree with it."
  (let ((tokens (if (join-node-index join)
                    (gethash (alpha-index-key (join-node-index join) (wme-fact wme))
                             (join-node-left-index join))
                    (beta-node-memory (beta-node-parent join)))))
    (when tokens
      (do-rset (token tokens)
        (join-attempt join token wme)))))

(defgeneric left-activate (node token)
  (:documentation "TOKEN entered the memory of NODE's parent: pass it through NODE."))

(defmethod left-activate ((join join-node) token)
  (let ((wmes (if (join-node-index join)
                  (let* ((key (token-key join token))
                         (table (join-node-left-index join)))
                    (rset-add (or (gethash key table) (setf (gethash key table) (make-rset)))
                              token)
                    (alpha-index-bucket (join-node-index join) key))
                  (alpha-memory-items (join-node-amem join)))))
    (when wmes
      (do-rset (wme wmes)
        (join-attempt join token wme)))))

(defmethod left-activate ((node prolog-node) token)
  (let* ((bindings (token-bindings token))
         (goal (prolog-node-goal node))
         (open (remove-if (lambda (var)
                            (let ((cell (assoc var bindings :test #'eq)))
                              (and cell (not (is-var (cdr cell))))))
                          (vars-in goal))))
    (dolist (solution (force-ll (prolog goal bindings)))
      (let ((new bindings))
        (dolist (var open)
          (let ((value (var-value var solution)))
            (unless (eq value var) (push (cons var value) new))))
        (add-token node token nil new)))))

(defmethod left-activate ((node production-node) token)
  (add-token node token nil (token-bindings token)))

(defun network-assert (wme)
  "Pass the new WME through the alpha memories it fits and their join nodes."
  (dolist (memory (matching-alpha-memories (wme-fact wme)))
    (alpha-memory-insert memory wme)
    (dolist (join (alpha-memory-successors memory))
      (right-activate join wme))))

(defun network-retract (wme)
  "Delete the tokens made with WME and remove it from its alpha memories."
  (dolist (token (rset-items (wme-tokens wme)))
    (delete-token token nil))
  (dolist (memory (wme-alpha-memories wme))
    (alpha-memory-delete memory wme))
  (setf (wme-alpha-memories wme) '()))

;;; Building and removing the chains of productions

(defun pattern-bound-vars (pattern)
  "The variables matching PATTERN binds: its ?variables and those of its segment variables."
  (let ((vars (vars-in pattern)))
    (labels ((walk (x)
               (cond ((is-segvar x)
                      (let ((var (var-name x)))
                        (unless (is-anonymous-var var) (pushnew var vars))))
                     ((consp x) (walk (car x)) (walk (cdr x))))))
      (walk pattern))
    vars))

(defun fill-node (node)
  "Pass the tokens of NODE's parent through NODE, which is new."
  (do-rset (token (beta-node-memory (beta-node-parent node)))
    (left-activate node token)))

(defun ensure-join-node (parent pattern bound maybe)
  "PARENT's join node for PATTERN: (values node t) for a new node, connected but not filled;
an existing node is shared. BOUND: the variables earlier fact patterns bind; MAYBE: those only
earlier Prolog patterns may bind."
  (let ((old (find-if (lambda (child)
                        (and (join-node-p child) (equal (join-node-pattern child) pattern)))
                      (beta-node-children parent))))
    (if old
        (values old nil)
        (let* ((memory (ensure-alpha-memory pattern))
               (join (make-join-node parent pattern memory)))
          (if (segmented-p pattern)
              (setf (join-node-segmented join) t)
              (loop for (var . path) in (variable-paths pattern)
                    if (member var bound) collect var into hash-vars and collect path into paths
                    else if (member var maybe) collect (cons var path) into dyn
                    else collect (cons var path) into new
                    finally (setf (join-node-dyn-vars join) dyn
                                  (join-node-new-vars join) new)
                            (when hash-vars
                              (setf (join-node-hash-vars join) hash-vars
                                    (join-node-index join) (acquire-alpha-index memory paths)
                                    (join-node-left-index join)
                                    (make-hash-table :test 'equal)))))
          ;; In front: a node is made after its ancestors, so the successors come descendants
          ;; first and a fact entering the memory is not joined twice with one token.
          (push join (alpha-memory-successors memory))
          (push join (beta-node-children parent))
          (values join t)))))

(defun ensure-prolog-node (parent goal)
  "PARENT's Prolog node for GOAL: (values node t) for a new node, connected but not filled; an
existing node is shared."
  (let ((old (find-if (lambda (child)
                        (and (prolog-node-p child) (equal (prolog-node-goal child) goal)))
                      (beta-node-children parent))))
    (if old
        (values old nil)
        (let ((node (make-prolog-node parent goal)))
          (push node (beta-node-children parent))
          (values node t)))))

(defun build-production-network (production)
  "Build (or share) the chain of PRODUCTION's patterns and its production node; its current
matches are queued as :ASSERT events. Returns the production node. When this fails, the nodes
made so far are removed again."
  (let ((node *beta-root*) (bound '()) (maybe '()) (done nil))
    (flet ((step-to (new-node new-p)
             (setf node new-node)
             (when new-p (fill-node node))))
      (unwind-protect
           (progn
             (dolist (pattern (production-patterns production))
               (if (prolog-pattern-p pattern)
                   (progn (multiple-value-call #'step-to (ensure-prolog-node node pattern))
                          (setf maybe (union maybe (vars-in pattern))))
                   (progn (multiple-value-call #'step-to (ensure-join-node node pattern bound maybe))
                          (setf bound (union bound (pattern-bound-vars pattern))))))
             (let ((end (make-production-node node production)))
               (push end (beta-node-children node))
               (step-to end t)
               (setf done t)
               end))
        (unless (or done (root-node-p node) (beta-node-children node))
          (remove-beta-node node))))))

(defun remove-beta-node (node)
  "Remove NODE (which has no children) with its tokens, silently, and the ancestors and alpha
memories left unused."
  (let ((*silent* t))
    (dolist (token (rset-items (beta-node-memory node)))
      (delete-token token nil)))
  (let ((parent (beta-node-parent node)))
    (setf (beta-node-children parent) (delete node (beta-node-children parent)))
    (when (join-node-p node)
      (let ((memory (join-node-amem node)))
        (setf (alpha-memory-successors memory) (delete node (alpha-memory-successors memory)))
        (when (join-node-index node)
          (release-alpha-index memory (join-node-index node)))
        (release-alpha-memory memory)))
    (when (and (not (root-node-p parent)) (null (beta-node-children parent)))
      (remove-beta-node parent))))

(defun map-beta-nodes (function &optional (node *beta-root*))
  "Call FUNCTION on every node below NODE (not on NODE)."
  (dolist (child (beta-node-children node))
    (funcall function child)
    (map-beta-nodes function child)))
