;;;; The alpha network: a discrimination tree over the constant structure of the patterns the
;;;; productions use, whose leaves hold alpha memories. A term is read in preorder as a sequence
;;;; of keys (a cons key, then its car, then its cdr; an atom is its own key); a pattern's
;;;; variables (and the sublists starting with a segment variable) are wildcards that stand for a
;;;; whole subterm. A fact walks down every branch whose key it has and every wildcard branch
;;;; (skipping the subterm), so it reaches only the memories whose patterns it can fit.
;;;;
;;;; An alpha memory holds the facts of the working memory that fit one pattern shape (the
;;;; pattern up to the names of its variables; see PATTERN-SHAPE): productions whose patterns
;;;; have the same shape share it. It keeps hash indexes of its facts by the values at given
;;;; places (ALPHA-INDEX), which join nodes use to find the facts that agree with a token.

(in-package :cram-prolog)

(defvar +cons-key+ (make-symbol "CONS") "The key of a cons in the key sequence of a term.")
(defvar +wildcard-key+ (make-symbol "ANY") "The key of a pattern's variable: any subterm.")

(defstruct (alpha-node (:constructor make-alpha-node (parent key)) (:copier nil))
  "A node of the discrimination tree: the KEY leading to it from PARENT, its CHILDREN (an EQUAL
hash table key → node, or NIL), its WILDCARD child and the alpha MEMORIES of the patterns that
end here."
  parent key (children nil) (wildcard nil) (memories '()))

(defvar *alpha-root* (make-alpha-node nil nil)
  "The root of the discrimination tree.")

(defstruct (alpha-memory (:constructor make-alpha-memory (shape leaf test)) (:copier nil))
  "The facts that fit the pattern SHAPE: its tree LEAF; TEST is true when the tree alone does not
decide (repeated variables, segment variables); ITEMS, an RSET of WMEs; SUCCESSORS, the join
nodes it right-activates, descendants before their ancestors; INDEXES, its ALPHA-INDEXes."
  shape leaf test (items (make-rset)) (successors '()) (indexes '()))

(defvar *alpha-memories* (make-hash-table :test 'equal)
  "Pattern shape → its ALPHA-MEMORY.")

(defstruct (alpha-index (:constructor make-alpha-index (paths)) (:copier nil))
  "The WMEs of an alpha memory hashed by the values at PATHS (see VARIABLE-PATHS): BUCKETS maps
the list of values (EQUAL) → an RSET of WMEs; USERS counts the join nodes using it."
  paths (buckets (make-hash-table :test 'equal)) (users 0 :type fixnum))

;;; Key sequences

(defun term-keys (term &optional pattern-p)
  "The preorder key sequence of TERM as a vector, and a vector giving for each position the
position after its subterm. With PATTERN-P, variables and segment forms are wildcards."
  (let ((keys (make-array 8 :adjustable t :fill-pointer 0))
        (ends (make-array 8 :adjustable t :fill-pointer 0)))
    (labels ((add (key)
               (vector-push-extend 0 ends)
               (vector-push-extend key keys))
             (wild-p (x)
               (and pattern-p (or (is-var x) (is-segform x))))
             (walk (x)
               (let ((spine '()))
                 (loop while (and (consp x) (not (wild-p x)))
                       do (push (add +cons-key+) spine)
                          (walk (car x))
                          (setf x (cdr x)))
                 (let ((i (add (if (wild-p x) +wildcard-key+ x))))
                   (setf (aref ends i) (1+ i)))
                 (dolist (j spine)
                   (setf (aref ends j) (fill-pointer keys))))))
      (walk term))
    (values keys ends)))

(defun alpha-leaf (shape)
  "The node of the discrimination tree where SHAPE's key sequence ends, made when missing."
  (let ((node *alpha-root*))
    (loop for key across (term-keys shape t)
          do (setf node
                   (if (eq key +wildcard-key+)
                       (or (alpha-node-wildcard node)
                           (setf (alpha-node-wildcard node) (make-alpha-node node key)))
                       (let ((table (or (alpha-node-children node)
                                        (setf (alpha-node-children node)
                                              (make-hash-table :test 'equal)))))
                         (or (gethash key table)
                             (setf (gethash key table) (make-alpha-node node key)))))))
    node))

(defun prune-alpha-node (node)
  "Remove NODE and its ancestors while they lead to no memory."
  (let ((parent (alpha-node-parent node)))
    (when (and parent
               (null (alpha-node-memories node))
               (null (alpha-node-wildcard node))
               (or (null (alpha-node-children node))
                   (zerop (hash-table-count (alpha-node-children node)))))
      (if (eq (alpha-node-key node) +wildcard-key+)
          (setf (alpha-node-wildcard parent) nil)
          (let ((table (alpha-node-children parent)))
            (remhash (alpha-node-key node) table)
            (when (zerop (hash-table-count table))
              (setf (alpha-node-children parent) nil))))
      (prune-alpha-node parent))))

(defun walk-alpha-tree (term pattern-p function)
  "Call FUNCTION on every alpha memory at the end of a branch TERM's keys lead to: each key's
branch and each wildcard branch (skipping the key's subterm). With PATTERN-P, TERM's variables
follow only wildcard branches."
  (multiple-value-bind (keys ends) (term-keys term pattern-p)
    (let ((n (length keys)))
      (labels ((visit (node i)
                 (if (= i n)
                     (mapc function (alpha-node-memories node))
                     (let ((key (aref keys i))
                           (children (alpha-node-children node))
                           (wildcard (alpha-node-wildcard node)))
                       (unless (eq key +wildcard-key+)
                         (let ((child (and children (gethash key children))))
                           (when child (visit child (1+ i)))))
                       (when wildcard (visit wildcard (aref ends i)))))))
        (visit *alpha-root* 0)))))

;;; Alpha memories

(defun alpha-memory-accepts-p (memory fact)
  "True when FACT, which reached MEMORY's leaf, fits its shape."
  (or (not (alpha-memory-test memory))
      (nth-value 1 (match-term (alpha-memory-shape memory) fact '()))))

(defun matching-alpha-memories (fact)
  "The alpha memories whose shapes FACT fits."
  (let ((result '()))
    (walk-alpha-tree fact nil (lambda (memory)
                                (when (alpha-memory-accepts-p memory fact)
                                  (push memory result))))
    result))

(defun freeze-pattern (pattern)
  "PATTERN with each ?_ replaced by a distinct constant, for SUBSUMES-P."
  (cond ((is-anonymous-var pattern) (make-symbol "ANY"))
        ((consp pattern) (cons (freeze-pattern (car pattern)) (freeze-pattern (cdr pattern))))
        (t pattern)))

(defun smallest-subsuming-memory (pattern)
  "The alpha memory with the fewest facts among those holding every fact that fits PATTERN
(their shapes are more general), or NIL."
  (unless (segmented-p pattern)
    (let ((best nil) (frozen (freeze-pattern pattern)))
      (walk-alpha-tree pattern t
                       (lambda (memory)
                         (when (and (or (null best)
                                        (< (rset-count (alpha-memory-items memory))
                                           (rset-count (alpha-memory-items best))))
                                    (nth-value 1 (match-term (alpha-memory-shape memory)
                                                             frozen '())))
                           (setf best memory))))
      best)))

(defun candidate-wmes (pattern)
  "WMEs among which are all those whose facts fit PATTERN, in the order of assertion: the
facts of the smallest alpha memory that holds them all, else the whole working memory."
  (let ((memory (smallest-subsuming-memory pattern)))
    (if memory
        (wmes-by-serial (rset-items (alpha-memory-items memory)))
        (all-wmes))))

(defun alpha-memory-insert (memory wme)
  "Add WME to MEMORY and its indexes (the join nodes are not activated here)."
  (rset-add (alpha-memory-items memory) wme)
  (push memory (wme-alpha-memories wme))
  (dolist (index (alpha-memory-indexes memory))
    (alpha-index-add index wme)))

(defun alpha-memory-delete (memory wme)
  "Remove WME from MEMORY and its indexes (WME's list of memories is left to the caller)."
  (rset-remove (alpha-memory-items memory) wme)
  (dolist (index (alpha-memory-indexes memory))
    (alpha-index-remove index wme)))

(defun ensure-alpha-memory (pattern)
  "The alpha memory of PATTERN's shape; a new one is filled from the working memory."
  (let ((shape (pattern-shape pattern)))
    (or (gethash shape *alpha-memories*)
        (let* ((candidates (candidate-wmes shape))
               (leaf (alpha-leaf shape))
               (memory (make-alpha-memory shape leaf (shape-needs-test-p shape))))
          (push memory (alpha-node-memories leaf))
          (setf (gethash shape *alpha-memories*) memory)
          (dolist (wme candidates)
            (when (nth-value 1 (match-term shape (wme-fact wme) '()))
              (alpha-memory-insert memory wme)))
          memory))))

(defun release-alpha-memory (memory)
  "Forget MEMORY once no join node uses it."
  (unless (alpha-memory-successors memory)
    (remhash (alpha-memory-shape memory) *alpha-memories*)
    (let ((leaf (alpha-memory-leaf memory)))
      (setf (alpha-node-memories leaf) (delete memory (alpha-node-memories leaf)))
      (do-rset (wme (alpha-memory-items memory))
        (setf (wme-alpha-memories wme) (delete memory (wme-alpha-memories wme))))
      (rset-clear (alpha-memory-items memory))
      (prune-alpha-node leaf))))

;;; Indexes

(defun alpha-index-key (index fact)
  "The list of the values at INDEX's paths in FACT."
  (mapcar (lambda (path) (value-at-path fact path)) (alpha-index-paths index)))

(defun alpha-index-add (index wme)
  "Add WME to its bucket of INDEX."
  (let* ((key (alpha-index-key index (wme-fact wme)))
         (buckets (alpha-index-buckets index)))
    (rset-add (or (gethash key buckets) (setf (gethash key buckets) (make-rset))) wme)))

(defun alpha-index-remove (index wme)
  "Remove WME from its bucket of INDEX; an empty bucket is dropped."
  (let* ((key (alpha-index-key index (wme-fact wme)))
         (buckets (alpha-index-buckets index))
         (bucket (gethash key buckets)))
    (when (and bucket (rset-remove bucket wme) (zerop (rset-count bucket)))
      (remhash key buckets))))

(defun alpha-index-bucket (index key)
  "The RSET of INDEX's WMEs whose values are KEY, or NIL."
  (gethash key (alpha-index-buckets index)))

(defun acquire-alpha-index (memory paths)
  "MEMORY's index by the values at PATHS (made and filled when missing), one more user counted."
  (let ((index (or (find paths (alpha-memory-indexes memory)
                         :key #'alpha-index-paths :test #'equal)
                   (let ((index (make-alpha-index paths)))
                     (do-rset (wme (alpha-memory-items memory))
                       (alpha-index-add index wme))
                     (push index (alpha-memory-indexes memory))
                     index))))
    (incf (alpha-index-users index))
    index))

(defun release-alpha-index (memory index)
  "One user less of INDEX; MEMORY drops it when none is left."
  (when (zerop (decf (alpha-index-users index)))
    (setf (alpha-memory-indexes memory) (delete index (alpha-memory-indexes memory)))))

(defun alpha-tree-size (&optional (node *alpha-root*))
  "The number of nodes of the discrimination tree below and at NODE."
  (+ 1
     (if (alpha-node-wildcard node) (alpha-tree-size (alpha-node-wildcard node)) 0)
     (if (alpha-node-children node)
         (loop for child being the hash-values of (alpha-node-children node)
               sum (alpha-tree-size child))
         0)))
