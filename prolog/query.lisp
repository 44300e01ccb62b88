;;;; The query API: PROLOG returns the lazy list of solutions of a goal.

(in-package :cram-prolog)

(defun final-continuation ()
  t)

(defun convert-binding-value (value env frame)
  "VALUE from an initial binding alist as a run-time term over FRAME's variables."
  (substitute-symbols value (lambda (sym)
                              (if (anonymous-var-p sym)
                                  (make-pvar)
                                  (svref frame (cdr (assoc sym env :test #'eq)))))))

(defun solution-alist (out frame env)
  "The binding alist of the output variables in FRAME, OUT listing their entries (?var . index)
of ENV: values fully substituted, unbound variables shown as ?symbols, variables without a value
left out."
  (if (loop for (nil . i) in out
            always (term-ground-p (svref frame i)))
      (loop for (sym . i) in out
            for value = (resolve-term (svref frame i))
            unless (eq value sym)
              collect (cons sym value))
      (named-solution-alist out frame env)))

(defun named-solution-alist (out frame env)
  "SOLUTION-ALIST when some values hold unbound variables."
  (let ((names '()) (counter 0))
    (flet ((name-of (v)
             (or (cdr (assoc v names :test #'eq))
                 (let ((sym (or (car (find v env :key (lambda (e) (svref frame (cdr e)))
                                             :test #'eq))
                                (make-symbol (format nil "?_G~d" (incf counter))))))
                   (push (cons v sym) names)
                   sym))))
      (loop for (sym . i) in out
            for value = (resolve-term (svref frame i) #'name-of)
            unless (eq value sym)
              collect (cons sym value)))))

(defun call-with-storage-guard (thunk)
  "Call THUNK and return its values. Running out of Lisp stack or heap inside it signals
PROLOG-RESOURCE-ERROR after unwinding THUNK and collecting the garbage it left."
  (let ((condition
          (handler-case (return-from call-with-storage-guard (funcall (the function thunk)))
            (prolog-resource-error (c) c)
            (storage-condition (c)
              (make-condition
               'prolog-resource-error
               :message (format nil "The Prolog query ran out of ~a: probably an endless ~
recursion or a term nested too deeply (hundreds of thousands of levels). The query was ~
abandoned; the image is unharmed."
                                (if (typep c 'sb-kernel::control-stack-exhausted)
                                    "Lisp stack (control stack exhausted)"
                                    (format nil "memory (~a)" (type-of c)))))))))
    ;; what the abandoned query held is garbage now; free it before anything else needs room
    (sb-ext:gc :full t)
    (error condition)))

(defmacro with-storage-guard (() &body body)
  "Run BODY; running out of Lisp stack or heap inside it signals PROLOG-RESOURCE-ERROR (after
unwinding BODY and collecting what it held)."
  (let ((thunk (gensym "GUARDED")))
    `(flet ((,thunk () ,@body))
       (declare (dynamic-extent #',thunk))
       (call-with-storage-guard #',thunk))))

(defun prolog (goal &optional bindings)
  "Prove GOAL (a term; ?symbols are variables) and return the lazy list of its solutions: binding
alists ((?var . value) ...) for the variables of GOAL and of BINDINGS, with values fully
substituted. NIL means no solution; (NIL) one solution binding nothing. BINDINGS, an alist of
initial values, constrains the query. Solutions are computed one at a time as the list is read:
only the first is computed before PROLOG returns."
  (unless (listp bindings)
    (prolog-error "PROLOG's bindings must be an alist ((?var . value) ...), got ~s." bindings))
  (dolist (b bindings)
    (unless (and (consp b) (is-var (car b)))
      (prolog-error "PROLOG's bindings must be an alist ((?var . value) ...); ~s is not a binding."
                    b)))
  (let* ((binding-vars (and bindings (remove-duplicates (mapcar #'car bindings) :from-end t)))
         (out (and bindings
                   (remove-if #'anonymous-var-p
                              (remove-duplicates (append (term-vars goal) binding-vars)
                                                 :from-end t)))))
    (multiple-value-bind (fn frame env)
        (with-storage-guard ()
          (compiled-goal goal (and bindings
                                   (append binding-vars (term-vars (mapcar #'cdr bindings))))))
      (let ((m (acquire-machine))
            (out (if out
                     (loop for sym in out collect (assoc sym env :test #'eq))
                     env))
            (state :fresh))
        ;; initial bindings; no choice point exists yet, so nothing needs trailing
        (with-storage-guard ()
          (dolist (b bindings)
            (unless (unify-terms m (svref frame (cdr (assoc (car b) env)))
                                 (convert-binding-value (cdr b) env frame))
              (setf state :done))))
        (when (eq state :done)
          (release-machine m))
        (make-lazy-list
         (lambda ()
           (if (eq state :done)
               (values nil nil)
               (let ((found nil) (finished nil))
                 (unwind-protect
                      (with-storage-guard ()
                        (setf found
                              (if (eq state :fresh)
                                  (progn (setf state :running)
                                         (or (funcall (the function fn) m frame
                                                      #'final-continuation 0)
                                             (backtrack m)))
                                  (backtrack m)))
                        (when found
                          (check-resources m)
                          (setf found (list (solution-alist out frame env))))
                        ;; without a choice point left, no further solution exists
                        (setf finished (zerop (machine-cp-top m))))
                   (when (or finished (not found))
                     (setf state :done)))
                 (when finished
                   (release-machine m))
                 (if found
                     (values (car found) t)
                     (values nil nil))))))))))

(defun filter-bindings (form bindings &optional initial-bindings)
  "INITIAL-BINDINGS extended by the values that BINDINGS (a superset of them, e.g. a solution of
a query made under them) gives to the variables of FORM and of INITIAL-BINDINGS: the bindings
of every other variable are left out. A variable of INITIAL-BINDINGS keeps its binding there,
and a variable that INITIAL-BINDINGS binds to another one gets its value through that one."
  (unless (and (listp bindings) (every #'consp bindings))
    (prolog-error "FILTER-BINDINGS: expected a binding alist ((?var . value) ...), got ~s." bindings))
  (unless (and (listp initial-bindings) (every #'consp initial-bindings))
    (prolog-error "FILTER-BINDINGS: expected initial bindings as an alist ((?var . value) ...), got ~s."
                  initial-bindings))
  (let ((result initial-bindings))
    (dolist (var (vars-in (cons form initial-bindings)) result)
      (unless (assoc var result)
        (let ((value (var-value var bindings)))
          (unless (eq value var)
            (push (cons var value) result)))))))
