;;;; Goals: functions whose definitions are chosen by matching the arguments
;;;; against patterns with ?variables.

(in-package :cram-language)

(defvar *goals* (make-hash-table :test 'eq)
  "Goal name -> list of goal definitions, in the order they were defined.")

(defvar *goals-lock* (bt:make-lock "cpl goals"))

(defstruct (goal-definition (:constructor make-goal-definition (pattern function)))
  pattern function)

(defun pattern-variable-p (object)
  (and (symbolp object) object (not (keywordp object))
       (> (length (symbol-name object)) 1)
       (char= (char (symbol-name object) 0) #\?)))

(defun pattern-variables (pattern)
  (let ((variables '()))
    (labels ((walk (p)
               (cond ((pattern-variable-p p) (pushnew p variables))
                     ((consp p) (walk (car p)) (walk (cdr p))))))
      (walk pattern))
    (nreverse variables)))

(defun match-pattern (pattern datum bindings)
  "Match DATUM against PATTERN; returns (values bindings matched-p)."
  (cond ((pattern-variable-p pattern)
         (let ((entry (assoc pattern bindings)))
           (cond ((null entry) (values (acons pattern datum bindings) t))
                 ((equal (cdr entry) datum) (values bindings t))
                 (t (values nil nil)))))
        ((and (consp pattern) (consp datum))
         (multiple-value-bind (car-bindings ok) (match-pattern (car pattern) (car datum) bindings)
           (if ok
               (match-pattern (cdr pattern) (cdr datum) car-bindings)
               (values nil nil))))
        ((equal pattern datum) (values bindings t))
        (t (values nil nil))))

(defun call-goal (name arguments)
  (let ((definitions (bt:with-lock-held (*goals-lock*)
                       (copy-list (gethash name *goals*)))))
    (dolist (definition definitions
             (error "No definition of the goal ~s matches the arguments ~s ~
                     (patterns: ~{~s~^, ~})."
                    name arguments (mapcar #'goal-definition-pattern definitions)))
      (multiple-value-bind (bindings ok)
          (match-pattern (goal-definition-pattern definition) arguments '())
        (when ok
          (return (with-task-tree-node (:goal name)
                    (funcall (goal-definition-function definition) bindings))))))))

(defmacro declare-goal (name lambda-list &body documentation-and-declarations)
  "Declare NAME as a goal function taking LAMBDA-LIST (required parameters
only). Its definitions are given with DEF-GOAL; a call runs the first
definition (in definition order) whose pattern matches the arguments."
  (unless (and (symbolp name) (listp lambda-list)
               (every (lambda (p) (and (symbolp p)
                                       (not (member p lambda-list-keywords))))
                      lambda-list))
    (error "DECLARE-GOAL: expected a name and a list of required parameters, got ~s ~s."
           name lambda-list))
  (let ((docstring (find-if #'stringp documentation-and-declarations)))
    `(progn
       (bt:with-lock-held (*goals-lock*)
         (unless (nth-value 1 (gethash ',name *goals*))
           (setf (gethash ',name *goals*) '())))
       (defun ,name ,lambda-list
         ,@(when docstring (list docstring))
         (call-goal ',name (list ,@lambda-list))))))

(defmacro def-goal ((name &rest pattern) &body body)
  "Define how to achieve the goal NAME (declared with DECLARE-GOAL) when its
arguments match PATTERN: symbols starting with ? match anything and are bound
in BODY (a repeated variable must match equal values), anything else must be
EQUAL to the argument. Redefining an EQUAL pattern replaces the definition.
BODY runs in a :GOAL node of the task tree."
  (unless (symbolp name)
    (error "DEF-GOAL: expected a goal name, got ~s." name))
  (let ((bindings (gensym "BINDINGS"))
        (variables (pattern-variables pattern)))
    `(progn
       (unless (nth-value 1 (gethash ',name *goals*))
         (error "DEF-GOAL: ~s is not a declared goal; use DECLARE-GOAL first." ',name))
       (register-goal-definition
        ',name ',pattern
        (lambda (,bindings)
          (declare (ignorable ,bindings))
          (let ,(loop for variable in variables
                      collect `(,variable (cdr (assoc ',variable ,bindings))))
            (declare (ignorable ,@variables))
            ,@body)))
       ',name)))

(defun register-goal-definition (name pattern function)
  (bt:with-lock-held (*goals-lock*)
    (let* ((definitions (gethash name *goals*))
           (existing (find pattern definitions :key #'goal-definition-pattern
                                               :test #'equal)))
      (if existing
          (setf (goal-definition-function existing) function)
          (setf (gethash name *goals*)
                (append definitions (list (make-goal-definition pattern function))))))))
