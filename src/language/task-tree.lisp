;;;; The task tree: one node per plan, action, motion or parallel child, with
;;;; timing, outcome, caught failures and retry counts.

(in-package :cram-language)

(defstruct (task-tree-node (:conc-name node-)
                           (:constructor %make-task-tree-node)
                           (:copier nil))
  "One node of the task tree recorded while a top-level plan runs."
  (kind :plan :type keyword)
  (name nil)
  (%designator nil)     ; the printed designator, or (function . package) until someone asks
  (parent nil)
  (%children '())
  (start-time 0 :type integer)
  (end-time nil)
  (start-unix 0d0 :type double-float)
  (end-unix nil)
  (outcome :running :type keyword)
  (failure nil)
  (%caught-failures '())
  (retries 0 :type integer)
  (%pictures '())
  (lock (bt:make-lock "task tree node")))

(setf (documentation 'node-kind 'function)
      "The kind of a task tree node: :TOP-LEVEL, :PLAN, :ACTION, :MOTION, :PAR, :PURSUE, :TRY-ALL, :PAR-CHILD or any keyword a layer uses."
      (documentation 'node-name 'function) "The name of a task tree node (a symbol or string)."
      (documentation 'node-parent 'function) "The parent node, NIL for the root."
      (documentation 'node-start-time 'function) "Monotonic clock time (microseconds) at which the node started."
      (documentation 'node-end-time 'function) "Monotonic clock time (microseconds) at which the node ended, NIL while it runs."
      (documentation 'node-start-unix 'function) "Unix time (seconds, double) at which the node started."
      (documentation 'node-end-unix 'function) "Unix time at which the node ended, NIL while it runs."
      (documentation 'node-outcome 'function) "One of :RUNNING, :SUCCEEDED, :FAILED, :EVAPORATED."
      (documentation 'node-failure 'function) "For a failed node, the plist (:CLASS symbol :DESCRIPTION string) of the failure that ended it."
      (documentation 'node-retries 'function) "How often WITH-FAILURE-HANDLING retried inside this node.")

(defmethod print-object ((node task-tree-node) stream)
  (print-unreadable-object (node stream :type t :identity t)
    (format stream "~(~a~) ~a ~(~a~)" (node-kind node) (node-name node) (node-outcome node))))

(defvar *task-tree-node* nil
  "The innermost task tree node of the running plan, NIL outside a top-level.")

(defvar *last-task-tree* nil
  "The root node of the task tree of the most recent top-level run.")

(defun node-children (node)
  "The child nodes of NODE in the order they were started."
  (bt:with-lock-held ((node-lock node))
    (reverse (node-%children node))))

(defun node-caught-failures (node)
  "The failures that WITH-FAILURE-HANDLING clauses inside NODE caught, oldest
first, each a plist (:CLASS symbol :DESCRIPTION string)."
  (bt:with-lock-held ((node-lock node))
    (reverse (node-%caught-failures node))))

(defun node-duration (node)
  "Seconds between start and end of NODE (up to now while it runs)."
  (/ (- (or (node-end-time node) (monotonic-microseconds)) (node-start-time node))
     1d6))

(defun failure-plist (condition)
  (list :class (type-of condition) :description (failure-description condition)))

(defun designator-string (designator)
  (cond ((null designator) nil)
        ((stringp designator) designator)
        (t (handler-case (let ((*print-length* 20) (*print-level* 6))
                           (prin1-to-string designator))
             (error () (format nil "<unprintable ~s>" (type-of designator)))))))

(defun node-designator (node)
  "The printed designator of a task tree node, or NIL. A node made with a function as its
designator calls it and prints its value (in the package current when the node was made) the
first time this is asked: a task tree nobody reads prints nothing."
  (let ((d (node-%designator node)))
    (if (consp d)
        (let ((text (let ((*package* (cdr d))) (designator-string (funcall (car d))))))
          (bt:with-lock-held ((node-lock node))
            (setf (node-%designator node) text)))
        d)))

(defun make-task-tree-node (kind name &key designator parent)
  "Create a running node, attached as the last child of PARENT when given. DESIGNATOR is
printed now, unless it is a function: then NODE-DESIGNATOR calls it when first asked (for a
value that does not change meanwhile)."
  (check-type kind keyword)
  (let ((node (%make-task-tree-node :kind kind :name name
                                    :%designator (if (functionp designator)
                                                     (cons designator *package*)
                                                     (designator-string designator))
                                    :parent parent
                                    :start-time (monotonic-microseconds)
                                    :start-unix (unix-time))))
    (when parent
      (bt:with-lock-held ((node-lock parent))
        (push node (node-%children parent))))
    node))

(defun node-pictures (node)
  "The pictures (path strings, oldest first) taken while NODE ran, noted with NOTE-PICTURE."
  (bt:with-lock-held ((node-lock node)) (reverse (node-%pictures node))))

(defun note-picture (path &optional (node *task-tree-node*))
  "Note that the picture at PATH shows the world as NODE (default: the current task tree node)
left it; the task tree page links it. Outside a plan this does nothing. Returns PATH."
  (when (and node path)
    (bt:with-lock-held ((node-lock node)) (push (namestring path) (node-%pictures node))))
  path)

(defun note-retry (node)
  "Count one retry in NODE."
  (when node
    (bt:with-lock-held ((node-lock node))
      (incf (node-retries node)))))

(defun note-caught-failure (node condition)
  "Record in NODE that CONDITION was caught by a failure handler."
  (when node
    (let ((entry (failure-plist condition)))
      (bt:with-lock-held ((node-lock node))
        (push entry (node-%caught-failures node))))))

(defun finish-node (node outcome failure)
  (sb-sys:without-interrupts
    (bt:with-lock-held ((node-lock node))
      (setf (node-end-time node) (monotonic-microseconds)
            (node-end-unix node) (unix-time)
            (node-outcome node) outcome
            (node-failure node) (and failure (failure-plist failure))))))

(defun run-in-node (node thunk)
  "Call THUNK with NODE as the current node, and record its outcome: succeeded
on a normal return (or a non-failure exit such as RETURN), failed when a
failure or error passed through unhandled, evaporated when the task was
evaporated."
  (let ((done nil) (failure nil))
    (unwind-protect
         (let ((*task-tree-node* node))
           (handler-bind ((plan-failure (lambda (c) (setf failure c)))
                          (error (lambda (c) (setf failure c))))
             (multiple-value-prog1 (funcall thunk)
               (setf done t))))
      (finish-node node
                   (cond (done :succeeded)
                         ((current-task-evaporating-p) :evaporated)
                         (failure :failed)
                         (t :succeeded))
                   (if done nil failure)))))

(defun call-with-task-tree-node (kind name designator thunk)
  "Run THUNK inside a new node of the current task tree; outside a top-level
just call THUNK."
  (let ((parent *task-tree-node*))
    (if parent
        (run-in-node (make-task-tree-node kind name :designator designator
                                                    :parent parent)
                     thunk)
        (funcall thunk))))

(defmacro with-task-tree-node ((kind name &key designator) &body body)
  "Run BODY as a node of kind KIND (a keyword such as :PLAN, :ACTION or
:MOTION), named NAME, in the task tree of the running top-level. DESIGNATOR,
when non-NIL, is stored as its printed representation. The node records start
and end times, its outcome, the failures caught inside it and its retries.
Outside a top-level BODY simply runs. Returns the values of BODY."
  `(call-with-task-tree-node ,kind ,name ,designator (lambda () ,@body)))

(defun find-task-tree-nodes (predicate &optional (root *last-task-tree*))
  "All nodes under and including ROOT (depth first, in start order) for which
PREDICATE returns true."
  (let ((result '()))
    (labels ((walk (node)
               (when (funcall predicate node) (push node result))
               (mapc #'walk (node-children node))))
      (when root (walk root)))
    (nreverse result)))
