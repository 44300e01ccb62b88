;;;; The current robot's name, and Lisp helpers over the robot-description facts.

(in-package :cram-robot-interfaces)

(defvar *robot-name* nil
  "The name of the robot the plans run on: the symbol its description's facts are keyed by
(:PR2, PEPPER-DESCR:PEPPER, ...), or NIL when none is chosen yet.  Set it with
SET-ROBOT-NAME; read it with CURRENT-ROBOT-NAME.")

(defvar *robot-urdf* nil
  "The parsed URDF model of the current robot, or NIL before the belief state reads it.")

(defparameter *robot-description-parameter* "robot_description"
  "The ROS parameter holding the robot's URDF, read when a ROS node runs.")

(defvar *environment-urdf* nil
  "The parsed URDF model of the environment (the kitchen, the shop), or NIL before the belief
state reads it.")

(defvar *environment-name-function* nil
  "A function of no arguments returning the name of the environment object of the current
belief state, or NIL; the belief state sets it.")

(defun get-environment-name ()
  "The name of the environment the robot acts in: the environment object of the current belief
state, else the keyword of *ENVIRONMENT-URDF*'s robot name (\"iai_kitchen\" gives
:IAI-KITCHEN), as *ENVIRONMENT-NAME-FUNCTION* finds them. Signals ROBOT-INTERFACE-ERROR when
there is none."
  (or (and *environment-name-function* (funcall *environment-name-function*))
      (robot-interface-error "No environment: the belief state has no environment object and ~
                              ~s is NIL." '*environment-urdf*)))

(defun get-robot-name ()
  "The name of the current robot (CRAM's name for CURRENT-ROBOT-NAME)."
  (current-robot-name))

(define-condition robot-interface-error (simple-error) ()
  (:documentation "Bad input to, or a missing fact behind, a robot-interface helper."))

(defun robot-interface-error (format-control &rest format-arguments)
  "Signal a ROBOT-INTERFACE-ERROR with the message FORMAT-CONTROL and FORMAT-ARGUMENTS."
  (error 'robot-interface-error :format-control format-control
                                :format-arguments format-arguments))

(defmacro define-predicate-documentation (&rest entries)
  "Attach documentation strings to Prolog predicate symbols.  Each entry is (SYMBOL TEXT);
the text is stored in the symbol's property list under PREDICATE-DOCUMENTATION, where
DESCRIBE shows it."
  `(progn
     ,@(loop for (symbol text) in entries
             do (check-type symbol symbol)
                (check-type text string)
             collect `(setf (get ',symbol 'predicate-documentation) ,text))
     ',(mapcar #'first entries)))

;;; Names

(defvar *loaded-robot-name-function* nil
  "A function of no arguments returning the name of the described robot that is loaded (in the
current belief state, or as *ROBOT-URDF*), or NIL; the belief state sets it. CURRENT-ROBOT-NAME
and the ROBOT predicate answer that robot while *ROBOT-NAME* is NIL.")

(defvar *all-described-robots* nil
  "True while DESCRIBED-ROBOT-NAMES asks for every described robot.")

(defun loaded-robot-name ()
  "The described robot that is loaded (see *LOADED-ROBOT-NAME-FUNCTION*), or NIL."
  (and (not *all-described-robots*) *loaded-robot-name-function*
       (let ((*all-described-robots* t))
         (ignore-errors (funcall *loaded-robot-name-function*)))))

(defun described-robot-names ()
  "Every robot name declared by a loaded robot description through (ROBOT ?NAME) facts,
in clause order, whatever the current robot is."
  (let ((*robot-name* nil) (*all-described-robots* t))
    (remove-duplicates
     (mapcar (lambda (bindings) (cut:var-value '?robot-name bindings))
             (cut:force-ll (prolog '(robot ?robot-name))))
     :from-end t)))

(defun current-robot-name ()
  "The name of the current robot: the value of *ROBOT-NAME*, else the described robot loaded in
the belief state (LOADED-ROBOT-NAME).  Signals ROBOT-INTERFACE-ERROR when there is none."
  (or *robot-name*
      (loaded-robot-name)
      (let ((described (described-robot-names)))
        (robot-interface-error
         "No current robot: ~s is NIL. Choose one with (rob-int:set-robot-name NAME), where ~
          NAME is the robot's URDF name (e.g. \"pr2\") or its description symbol; ~
          ~:[no robot description is loaded~;the loaded descriptions declare ~:*~{~s~^, ~}~]."
         '*robot-name* described))))

(defun urdf-name->robot-name (urdf-name)
  "The keyword a URDF <robot name> maps to by convention: underscores become hyphens and
the result is upcased, so \"pr2\" gives :PR2 and \"iai_donbot\" gives :IAI-DONBOT."
  (unless (and (stringp urdf-name)
               (plusp (length (string-trim " " urdf-name))))
    (robot-interface-error "Expected a non-empty URDF robot name string, got ~s." urdf-name))
  (intern (string-upcase (substitute #\- #\_ (string-trim " " urdf-name))) :keyword))

(defun matching-described-name (name described)
  "The symbol of DESCRIBED that NAME (a string or symbol) designates, or NIL."
  (or (and (symbolp name) (find name described))
      (let* ((text (if (symbolp name) (symbol-name name) name))
             (keyword-text (symbol-name (urdf-name->robot-name text))))
        (find-if (lambda (robot)
                   (or (string-equal (symbol-name robot) text)
                       (string-equal (symbol-name robot) keyword-text)))
                 described))))

(defun set-robot-name (name &key (require-description t))
  "Make the robot designated by NAME the current robot and return its name symbol.
NAME is a URDF robot name string (\"pr2\", \"pepper\") or a symbol (:PR2, PEPPER-DESCR:PEPPER).
It is matched case-insensitively, with underscores read as hyphens, against the names the
loaded descriptions declare through (ROBOT ?NAME), so \"pr2\" selects :PR2 and \"pepper\"
selects PEPPER-DESCR:PEPPER.  When no description declares it, a ROBOT-INTERFACE-ERROR is
signalled, unless REQUIRE-DESCRIPTION is NIL: then the name is used as given (a string by
the convention of URDF-NAME->ROBOT-NAME)."
  (unless (or (stringp name) (and name (symbolp name)))
    (robot-interface-error "Expected a robot name (a URDF name string or a symbol), got ~s."
                           name))
  (when (and (stringp name) (zerop (length (string-trim " " name))))
    (robot-interface-error "Expected a non-empty robot name, got ~s." name))
  (let* ((described (described-robot-names))
         (match (matching-described-name name described)))
    (cond (match (setf *robot-name* match))
          (require-description
           (robot-interface-error
            "No loaded robot description declares the robot ~s; ~:[no description is ~
             loaded~;the loaded descriptions declare ~:*~{~s~^, ~}~]. Load its description ~
             system, or pass :require-description nil."
            name described))
          ((stringp name) (setf *robot-name* (urdf-name->robot-name name)))
          (t (setf *robot-name* name)))))

;;; Facts as Lisp values

;;; Answers of queries over plain facts, kept while the database is the same

(defvar *fact-answers* (make-hash-table :test 'equal :synchronized t)
  "Query → (database generation . every solution, or :NOT-PLAIN) of the fact queries asked
through CACHED-FACT-SOLUTIONS.")

(defparameter *fact-answers-size* 1000
  "The most queries *FACT-ANSWERS* keeps (it is emptied when it holds more).")

(defun plain-facts-p (functor)
  "True when every clause of FUNCTOR is a fact without a body (or a default clause whose body is
just FAIL, as the robot interfaces declare their functors): its answers depend on the database
alone (no Lisp, no special variable, no world state)."
  (let ((clauses (prolog:predicate-clauses functor)))
    (and clauses
         (every (lambda (c)
                  (or (null (cdr c))
                      (and (null (cddr c)) (consp (second c)) (null (cdr (second c)))
                           (string= (symbol-name (car (second c))) "FAIL"))))
                clauses)
         (null (prolog::pred-handler (gethash functor prolog::*predicates*))))))

(defun cached-fact-solutions (query)
  "Every solution of QUERY when it asks about plain facts (PLAIN-FACTS-P), kept until the
database changes (plans and motions ask the same few questions about the robot many times);
second value NIL for any other query, which the caller then runs itself."
  (let ((generation (prolog:database-generation))
        (cached (gethash query *fact-answers*)))
    (cond ((and cached (eql (car cached) generation))
           (if (eq (cdr cached) :not-plain) (values nil nil) (values (cdr cached) t)))
          (t
           (when (> (hash-table-count *fact-answers*) *fact-answers-size*)
             (clrhash *fact-answers*))
           (if (and (consp query) (symbolp (car query)) (plain-facts-p (car query)))
               (let ((solutions (cut:force-ll (prolog query))))
                 (setf (gethash (copy-tree query) *fact-answers*) (cons generation solutions))
                 (values solutions t))
               (progn (setf (gethash (copy-tree query) *fact-answers*) (cons generation :not-plain))
                      (values nil nil)))))))

(defun fact-solutions (query)
  "The solutions of QUERY: kept ones for a query over plain facts (CACHED-FACT-SOLUTIONS), else
those of PROLOG (a lazy list)."
  (multiple-value-bind (solutions cached) (cached-fact-solutions query)
    (if cached solutions (prolog query))))

(defun first-solution-value (variable query)
  "The value of VARIABLE in the first solution of QUERY, and whether there was one."
  (let ((solutions (fact-solutions query)))
    (if solutions
        (values (cut:var-value variable (cut:lazy-car solutions)) t)
        (values nil nil))))

(defun robot-arms (robot)
  "The arms ROBOT has according to the ARM facts."
  (mapcar (lambda (bindings) (cut:var-value '?arm bindings))
          (cut:force-ll (fact-solutions `(arm ,robot ?arm)))))

(defun arm-fact-value (predicate robot arm)
  "The value of the (PREDICATE ROBOT ARM ?value) fact; ROBOT-INTERFACE-ERROR naming PREDICATE,
ROBOT, ARM and the robot's arms when there is none."
  (multiple-value-bind (value found) (first-solution-value '?value `(,predicate ,robot ,arm ?value))
    (unless found
      (robot-interface-error "Robot ~s has no ~a fact for the arm ~s; its arms are ~s."
                             robot predicate arm (robot-arms robot)))
    value))

(defun get-arm-joints (robot arm)
  "The joint names of ARM of ROBOT in kinematic order, from the ARM-JOINTS facts.
Signals ROBOT-INTERFACE-ERROR when the robot has no such arm."
  (arm-fact-value 'arm-joints robot arm))

(defun get-arm-links (robot arm)
  "The link names of ARM of ROBOT in kinematic order, from the ARM-LINKS facts.
Signals ROBOT-INTERFACE-ERROR when the robot has no such arm."
  (arm-fact-value 'arm-links robot arm))

(defun get-robot-joint-states (robot joints-type joints-id state-name)
  "The named configuration STATE-NAME (e.g. :PARK) of the JOINTS-TYPE (:ARM, :NECK) part
JOINTS-ID (:LEFT, :RIGHT) of ROBOT, as a list of (joint-name value) pairs, from the
ROBOT-JOINT-STATES facts.  Signals ROBOT-INTERFACE-ERROR when there is none."
  (multiple-value-bind (states found)
      (first-solution-value '?joint-states
                            `(robot-joint-states ,robot ,joints-type ,joints-id ,state-name
                                                 ?joint-states))
    (unless found
      (let ((known (remove-duplicates
                    (mapcar (lambda (bindings) (cut:var-value '?name bindings))
                            (cut:force-ll
                             (prolog `(robot-joint-states ,robot ,joints-type ,joints-id
                                                          ?name ?_)))))))
        (robot-interface-error
         "Robot ~s has no joint states named ~s for ~s ~s; the known names there are ~s."
         robot state-name joints-type joints-id known)))
    states))
