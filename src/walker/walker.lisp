;;;; A code walker for plans: EXPAND-PLAN macroexpands a form and builds the tree of the plans
;;;; it calls (functions defined with CPL:DEF-CRAM-FUNCTION or DEF-PLAN, expanded in turn) and
;;;; of the (:TAG name ...) forms in them; WALK-WITH-TAG-HANDLER reports the tags of a form.

(in-package :cram-walker)

(defstruct (plan-tree-node (:copier nil))
  "A node of a plan tree: the SEXP of a plan call or :TAG form (the walked form at the root), the
PATH of the node (innermost first, each step (plan-name) or (TAGGED name)), its PARENT and
CHILDREN in the order they appear."
  (sexp nil) (path nil) (parent nil) (children nil))

(defmethod print-object ((node plan-tree-node) stream)
  (print-unreadable-object (node stream :type t)
    (format stream "~s ~d children" (plan-tree-node-path node)
            (length (plan-tree-node-children node)))))

(setf (documentation 'plan-tree-node-sexp 'function) "The form of a plan tree node."
      (documentation 'plan-tree-node-path 'function) "The path of a plan tree node, innermost first."
      (documentation 'plan-tree-node-parent 'function) "The parent of a plan tree node (NIL at the root)."
      (documentation 'plan-tree-node-children 'function) "The children of a plan tree node, in order."
      (documentation 'make-plan-tree-node 'function) "Make a PLAN-TREE-NODE (keys :SEXP :PATH :PARENT :CHILDREN)."
      (documentation 'plan-tree-node-p 'function) "True for a PLAN-TREE-NODE.")

(defvar *plans* (make-hash-table :test 'eq)
  "Plan name → (lambda-list . body) of the plans EXPAND-PLAN expands.")

(defun register-plan (name lambda-list body)
  "Make the plan NAME (defined with LAMBDA-LIST and BODY) known to EXPAND-PLAN."
  (check-type name symbol)
  (setf (gethash name *plans*) (cons lambda-list body))
  name)

(defun plan-definition (name)
  "(values lambda-list body) of the registered plan NAME, or NIL."
  (let ((entry (gethash name *plans*)))
    (values (car entry) (cdr entry) (and entry t))))

(defun find-plan-node (plan-tree path)
  "The node of PLAN-TREE at PATH (innermost step first, as PLAN-TREE-NODE-PATH gives it, relative
to the root); NIL when there is none."
  (unless (and (listp path) (alexandria:proper-list-p path))
    (error "FIND-PLAN-NODE: the path ~s is not a list of steps." path))
  (unless (or (null plan-tree) (plan-tree-node-p plan-tree))
    (error "FIND-PLAN-NODE: ~s is not a plan tree (see EXPAND-PLAN)." plan-tree))
  (when plan-tree
    (if (null path)
        plan-tree
        (let ((step (car (last path))))
          (dolist (child (plan-tree-node-children plan-tree) nil)
            (when (equal step (car (plan-tree-node-path child)))
              (return (find-plan-node child (butlast path)))))))))

;;; The walk. The lexical environment is a list of entries (:macro name expander),
;;; (:function name) (a local function shadowing a plan) and (:symbol-macro name expansion).

(defvar *tag-handlers* '() "Functions (name body) called for every :TAG form walked.")
(defvar *parent* nil "The plan tree node that plan calls and tags found now belong to.")
(defvar *expanding* '() "The plans being expanded (no endless recursion).")

(defun local-entry (kind name env)
  (find-if (lambda (e) (and (eq (first e) kind) (eq (second e) name))) env))

(defun shadowed-p (name env)
  (find-if (lambda (e) (and (member (first e) '(:macro :function)) (eq (second e) name))) env))

(defun add-child (sexp step)
  (let ((node (make-plan-tree-node :sexp sexp :parent *parent*
                                   :path (cons step (and *parent* (plan-tree-node-path *parent*))))))
    (when *parent*
      (setf (plan-tree-node-children *parent*)
            (append (plan-tree-node-children *parent*) (list node))))
    node))

(defun local-expander (lambda-list body)
  (let ((form (gensym "FORM")))
    (compile nil `(lambda (,form) (destructuring-bind ,lambda-list (cdr ,form) ,@body)))))

(defun walk-body (forms env) (mapcar (lambda (f) (walk f env)) forms))

(defun walk-bindings (bindings env)
  (dolist (b bindings)
    (when (and (consp b) (consp (cdr b))) (walk (second b) env))))

(defun walk-function-definitions (definitions env)
  (dolist (d definitions)
    (when (consp d) (walk-body (cddr d) env))))

(defun walk (form env)
  "Walk FORM in the lexical environment ENV: report tags, record plan calls, expand macros."
  (cond ((symbolp form)
         (let ((entry (local-entry :symbol-macro form env)))
           (when entry (walk (third entry) env))))
        ((atom form))
        ((not (symbolp (car form)))
         (when (and (consp (car form)) (eq (caar form) 'lambda))
           (walk-body (cddr (car form)) env))
         (walk-body (cdr form) env))
        (t
         (let* ((head (car form)) (local-macro (local-entry :macro head env)))
           (cond
             ((eq head :tag)
              (unless (and (consp (cdr form)) (symbolp (second form)))
                (error "WALKER: malformed tag form ~s; expected (:TAG name form...)." form))
              (dolist (handler *tag-handlers*) (funcall handler (second form) (cddr form)))
              (let ((*parent* (if *parent* (add-child form (list 'tagged (second form))) *parent*)))
                (walk-body (cddr form) env)))
             (local-macro (walk (funcall (third local-macro) form) env))
             ((eq head 'quote))
             ((eq head 'function)
              (let ((f (second form)))
                (when (and (consp f) (eq (car f) 'lambda)) (walk-body (cddr f) env))))
             ((member head '(let let*))
              (walk-bindings (second form) env)
              (walk-body (cddr form) (remove-if (lambda (e) (and (eq (first e) :symbol-macro)
                                                                 (member (second e) (mapcar (lambda (b) (if (consp b) (car b) b)) (second form)))))
                                                env)))
             ((member head '(flet labels))
              (let ((inner (append (mapcar (lambda (d) (list :function (car d))) (second form)) env)))
                (walk-function-definitions (second form) (if (eq head 'labels) inner env))
                (walk-body (cddr form) inner)))
             ((eq head 'macrolet)
              (walk-body (cddr form)
                         (append (mapcar (lambda (d) (list :macro (first d)
                                                           (local-expander (second d) (cddr d))))
                                         (second form))
                                 env)))
             ((eq head 'symbol-macrolet)
              (walk-body (cddr form)
                         (append (mapcar (lambda (d) (list :symbol-macro (first d) (second d)))
                                         (second form))
                                 env)))
             ((and (not (shadowed-p head env)) (nth-value 2 (plan-definition head)))
              (walk-body (cdr form) env)
              (let ((*parent* (add-child form (list head))))
                (unless (member head *expanding*)
                  (let ((*expanding* (cons head *expanding*)))
                    (walk-body (nth-value 1 (plan-definition head)) '())))))
             ((and (not (shadowed-p head env)) (macro-function head)
                   (not (special-operator-p head)))
              (walk (macroexpand-1 form) env))
             (t (walk-body (cdr form) env)))))))

(defun expand-plan (form)
  "Walk FORM: macroexpand it and, at every call of a registered plan (CPL:DEF-CRAM-FUNCTION,
DEF-PLAN), expand that plan's body in turn. Returns the plan tree: a root node for FORM whose
descendants are the plan calls and (:TAG name ...) forms met, each with its PATH."
  (let ((*parent* (make-plan-tree-node :sexp form)) (*expanding* '()))
    (walk form '())
    *parent*))

(defun walk-with-tag-handler (form tag-handler &optional env)
  "Walk FORM and call TAG-HANDLER with the name and the body of every (:TAG name form...) form
in it (also inside macros), in order. ENV is accepted for CRAM's signature and ignored.
Returns FORM."
  (declare (ignore env))
  (let ((*tag-handlers* (cons tag-handler *tag-handlers*)) (*parent* nil))
    (walk form '())
    form))
