;;;; Tests of the executive layer: PERFORM, process modules, events, occasions, projection.

(defpackage :cram-executive-tests
  (:use :cl :fiveam))

(in-package :cram-executive-tests)

(def-suite executive :in cram-plans-tests:all
  :description "PERFORM, process modules, events and occasions, projection environments.")

(in-suite executive)

;;; Plans, process modules and groundings used by the tests

(defvar *plan-calls* '())

(defun exe-test-lift (&rest arguments &key type weight object &allow-other-keys)
  "Record the keyword arguments the action grounding passes."
  (declare (ignore type weight object))
  (push arguments *plan-calls*)
  :lifted)

(defun exe-test-add (a b)
  "A plan function taking positional arguments."
  (push (list a b) *plan-calls*)
  (+ a b))

(defvar *occasion-state* '())

(defun exe-test-occasion-p (x)
  (member x *occasion-state*))

(cpm:def-process-module exe-test-arm-pm (motion)
  "Moves nothing; answers with the motion's grounding."
  (list :arm-pm (desig:reference motion)))

(cpm:def-process-module exe-test-base-pm (motion)
  (list :base-pm (desig:reference motion)))

(cpm:def-process-module exe-test-failing-pm (motion)
  (declare (ignore motion))
  (cpl:fail "exe-test-failing-pm always fails"))

(prolog:def-fact-group executive-test-rules (desig:action-grounding desig:motion-grounding
                                             cpm:matching-process-module)
  (prolog:<- (desig:action-grounding ?d (exe-test-lift ?d))
    (desig:desig-prop ?d (:type :exe-test-lifting)))
  (prolog:<- (desig:action-grounding ?d (exe-test-add ?a ?b))
    (desig:desig-prop ?d (:type :exe-test-adding))
    (desig:desig-prop ?d (:a ?a))
    (desig:desig-prop ?d (:b ?b)))
  (prolog:<- (desig:action-grounding ?d (exe-test-undefined-plan ?d))
    (desig:desig-prop ?d (:type :exe-test-undefined)))
  (prolog:<- (desig:motion-grounding ?d (reach ?x))
    (desig:desig-prop ?d (:type :exe-test-reaching))
    (desig:desig-prop ?d (:target ?x)))
  (prolog:<- (desig:motion-grounding ?d (drive ?x))
    (desig:desig-prop ?d (:type :exe-test-driving))
    (desig:desig-prop ?d (:target ?x)))
  (prolog:<- (cpm:matching-process-module ?d exe-test-arm-pm)
    (desig:desig-prop ?d (:type :exe-test-reaching)))
  (prolog:<- (cpm:matching-process-module ?d exe-test-failing-pm)
    (desig:desig-prop ?d (:type :exe-test-driving)))
  (prolog:<- (cpm:matching-process-module ?d exe-test-base-pm)
    (desig:desig-prop ?d (:type :exe-test-driving))))

(prolog:def-fact-group executive-test-occasions ()
  (prolog:<- (exe-test-occasion ?x)
    (prolog:lisp-pred exe-test-occasion-p ?x)))

;;; Actions

(test perform-action-calls-plan-with-properties
  (let* ((*plan-calls* '())
         (?object (desig:an object (type bottle)))
         (d (desig:an action (type exe-test-lifting) (weight 2) (object ?object))))
    (is (eq :lifted (exe:perform d)))
    (is (= 1 (length *plan-calls*)))
    (let ((arguments (first *plan-calls*)))
      (is (eq :exe-test-lifting (getf arguments :type)))
      (is (eql 2 (getf arguments :weight)))
      (is (eq (desig:desig-prop-value d :object) (getf arguments :object)))
      (is (typep (getf arguments :object) 'desig:object-designator)))))

(test perform-action-positional-arguments
  (let ((*plan-calls* '()))
    (is (= 7 (exe:perform (desig:an action (type exe-test-adding) (a 3) (b 4)))))
    (is (equal '((3 4)) *plan-calls*))))

(test perform-action-errors
  (let* ((d (desig:an action (type exe-test-no-such-action)))
         (text (handler-case (progn (exe:perform d) "")
                 (desig:designator-error (e) (princ-to-string e)))))
    (is (search "EXE-TEST-NO-SUCH-ACTION" text)))
  (let ((text (handler-case (progn (exe:perform (desig:an action (type exe-test-undefined))) "")
                (desig:designator-error (e) (princ-to-string e)))))
    (is (search "EXE-TEST-UNDEFINED-PLAN" text)))
  (signals error (exe:perform 42))
  (signals error (exe:perform (desig:a location (pose 1)))))

(test perform-action-goal-skips
  (let* ((*plan-calls* '())
         (*occasion-state* '(1))
         (cpl:*log-stream* (make-broadcast-stream))
         (?goal '(exe-test-occasion 1))
         (d (desig:an action (type exe-test-lifting) (goal ?goal))))
    (is (null (exe:perform d)))
    (is (null *plan-calls*))
    (setf *occasion-state* '())
    (let ((result (exe:perform (desig:an action (type exe-test-lifting) (goal ?goal)))))
      (is (eq :lifted result)))
    (is (= 1 (length *plan-calls*)))))

(test holds-occasions
  (let ((*occasion-state* '(:here)))
    (is (not (null (coe:holds '(exe-test-occasion :here)))))
    (is (null (coe:holds '(exe-test-occasion :there))))
    (is (null (coe:holds '(cpoe:object-in-hand :bottle :left))))
    ;; a declared occasion no belief layer gives rules (ARMS-POSITIONED-AT has PP-PLANS's)
    (is (null (coe:holds '(cpoe:tool-frames-at nil nil))))
    (signals coe:occasion-functor-error (coe:holds 42))))

;;; Motions and process modules

(test perform-motion-dispatches-to-process-module
  (let ((?target 0.5))
    (cpm:with-process-modules-running (exe-test-arm-pm)
      (is (cpm:process-module-running-p 'exe-test-arm-pm))
      (is (equal '(:arm-pm (reach 0.5))
                 (exe:perform (desig:a motion (type exe-test-reaching) (target ?target))))))
    (is (not (cpm:process-module-running-p 'exe-test-arm-pm)))))

(test perform-motion-tries-matching-modules-in-order
  (let ((cpl:*log-stream* (make-broadcast-stream)))
    (cpm:with-process-modules-running (exe-test-failing-pm exe-test-base-pm)
      (is (equal '(exe-test-failing-pm exe-test-base-pm)
                 (cpm:matching-process-modules
                  (desig:a motion (type exe-test-driving) (target 1)))))
      (is (equal '(:base-pm (drive 1))
                 (exe:perform (desig:a motion (type exe-test-driving) (target 1))))))
    (cpm:with-process-modules-running (exe-test-failing-pm)
      (signals cpl:plan-failure
        (exe:perform (desig:a motion (type exe-test-driving) (target 1)))))))

(test perform-motion-without-matching-module
  (let* ((d (desig:a motion (type exe-test-reaching) (target 1)))
         (failure (handler-case (progn (exe:perform d) nil)
                    (cpm:no-matching-process-module (e) e))))
    (is (typep failure 'cpm:no-matching-process-module))
    (is (eq d (cpm:no-matching-process-module-designator failure)))
    (is (search "EXE-TEST-REACHING" (princ-to-string failure))))
  (cpm:with-process-modules-running (exe-test-base-pm)
    (signals cpm:no-matching-process-module
      (exe:perform (desig:a motion (type exe-test-reaching) (target 1))))))

(test process-module-errors
  (signals cpm:process-module-error
    (eval '(cpm:with-process-modules-running (exe-test-no-such-pm) t)))
  (signals cpm:process-module-error
    (cpm:pm-execute 'exe-test-arm-pm (desig:a motion (type exe-test-reaching) (target 1))))
  (is (member 'exe-test-arm-pm (cpm:process-module-names))))

;;; Events

(defclass exe-test-event (cpoe:robot-state-changed) ())

(defvar *event-log* '())

(defmethod coe:on-event exe-test-first-handler ((event exe-test-event))
  (push :first *event-log*)
  :first)

(defmethod coe:on-event exe-test-second-handler ((event exe-test-event))
  (push :second *event-log*)
  :second)

(defmethod coe:on-event exe-test-general-handler ((event cpoe:robot-state-changed))
  (push :general *event-log*)
  :general)

(test on-event-runs-every-handler
  (let ((*event-log* '()))
    (let ((results (coe:on-event (make-instance 'exe-test-event))))
      (is (subsetp '(:first :second :general) results))
      (is (= 3 (length *event-log*)))
      (is (subsetp '(:first :second :general) *event-log*))
      (is (eq :general (first *event-log*)))))
  (let ((*event-log* '()))
    (coe:on-event (make-instance 'cpoe:robot-state-changed))
    (is (equal '(:general) *event-log*)))
  (signals error (coe:on-event :not-an-event)))

(test event-slots-checked
  (let* ((object (desig:an object (type bottle)))
         (event (make-instance 'cpoe:object-attached-robot :object-name 'bottle-1 :arm :right
                                                           :grasp :front
                                                           :object-designator object)))
    (is (eq 'bottle-1 (cpoe:event-object-name event)))
    (is (eq :right (cpoe:event-arm event)))
    (is (eq :front (cpoe:event-grasp event)))
    (is (eq object (cpoe:event-object-designator event)))
    (is (realp (coe:event-timestamp event))))
  (signals error (make-instance 'cpoe:object-attached-robot :arm :left))
  (signals error (make-instance 'cpoe:object-attached-robot :object-name 42 :arm :left))
  (signals error (make-instance 'cpoe:object-perceived-event :object-designator :bottle))
  (signals error (make-instance 'cpoe:object-location-changed
                                :object-designator (desig:an object (type cup))
                                :location-designator "here")))

;;; Projection environments

(defvar *exe-test-special* :global)
(defvar *exe-test-shutdowns* 0)

(proj:define-projection-environment exe-test-projection
  :special-variable-initializers ((*exe-test-special* (list :projected (+ 1 2))))
  :process-module-definitions (exe-test-arm-pm exe-test-base-pm)
  :startup (setf *exe-test-special* (append *exe-test-special* '(:started)))
  :shutdown (incf *exe-test-shutdowns*))

(test projection-environment-binds-and-runs-modules
  (let ((*exe-test-shutdowns* 0))
    (proj:with-projection-environment exe-test-projection
      (is (eq 'exe-test-projection proj:*projection-environment*))
      (is (equal '(:projected 3 :started) *exe-test-special*))
      (is (equal '(:arm-pm (reach 2))
                 (exe:perform (desig:a motion (type exe-test-reaching) (target 2))))))
    (is (eq :global *exe-test-special*))
    (is (null proj:*projection-environment*))
    (is (= 1 *exe-test-shutdowns*))
    (ignore-errors (proj:with-projection-environment exe-test-projection (error "leave")))
    (is (= 2 *exe-test-shutdowns*))
    (is (member 'exe-test-projection (proj:projection-environment-names)))
    (signals error (proj:with-projection-environment exe-test-no-such-environment t))))

(test projection-environment-in-plan-tasks
  (let ((?target 3))
    (proj:with-projection-environment exe-test-projection
      (let ((results (cpl:top-level
                       (cpl:par
                         (exe:perform (desig:a motion (type exe-test-reaching) (target ?target)))
                         (list *exe-test-special*
                               (exe:perform (desig:an action (type exe-test-adding)
                                                             (a 1) (b 2))))))))
        (is (equal '((:projected 3 :started) 3) results))))))

(test perform-records-task-tree
  (let ((?target 4))
    (proj:with-projection-environment exe-test-projection
      (cpl:top-level
        (exe:perform (desig:a motion (type exe-test-reaching) (target ?target)))
        (exe:perform (desig:an action (type exe-test-adding) (a 1) (b 1)))))
    (let ((motions (cpl:find-task-tree-nodes
                    (lambda (n) (eq :motion (cpl:node-kind n)))))
          (actions (cpl:find-task-tree-nodes
                    (lambda (n) (eq :action (cpl:node-kind n)))))
          (plans (cpl:find-task-tree-nodes
                  (lambda (n) (and (eq :plan (cpl:node-kind n))
                                   (eq 'exe-test-add (cpl:node-name n)))))))
      (is (= 1 (length motions)))
      (is (eq :exe-test-reaching (cpl:node-name (first motions))))
      (is (search "EXE-TEST-REACHING" (cpl:node-designator (first motions))))
      (is (eq :succeeded (cpl:node-outcome (first motions))))
      (is (= 1 (length actions)))
      (is (= 1 (length plans)))
      (is (eq (first actions) (cpl:node-parent (first plans)))))))

;;; Retry strategies over designator solutions

(test retry-with-designator-solutions-walks-locations
  (let* ((?poses '((0 0 0) (0.01 0 0) (1 0 0) (2 0 0)))
         (tried '())
         (cpl:*log-stream* (make-broadcast-stream)))
    (cpl:top-level
      (let ((location (desig:a location (poses ?poses))))
        (cpl:with-retry-counters ((retries 3))
          (cpl:with-failure-handling
              ((cpl:simple-plan-failure (e)
                 (common-fail:retry-with-loc-designator-solutions location retries
                     (:error-object-or-string e))))
            (push (desig:reference location) tried)
            (unless (equal '(2 0 0) (desig:reference location))
              (cpl:fail "not there yet"))))))
    (is (equal '((0 0 0) (1 0 0) (2 0 0)) (reverse tried)))))
