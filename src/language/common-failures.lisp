;;;; Package CRAM-COMMON-FAILURES (nickname COMMON-FAIL): the failure classes
;;;; that robot plans signal and handle.

(defpackage :cram-common-failures
  (:nicknames :common-fail)
  (:use :cl)
  (:export
   #:description #:perception-failure-object
   #:low-level-failure
   #:actionlib-action-timed-out
   #:manipulation-low-level-failure #:manipulation-goal-not-reached
   #:manipulation-pose-unreachable #:environment-manipulation-goal-not-reached
   #:torso-low-level-failure #:torso-goal-unreachable #:torso-goal-not-reached
   #:gripper-low-level-failure #:gripper-closed-completely #:gripper-goal-not-reached
   #:navigation-low-level-failure #:navigation-pose-unreachable
   #:navigation-goal-not-reached
   #:ptu-low-level-failure #:ptu-goal-unreachable #:ptu-goal-not-reached
   #:perception-low-level-failure #:perception-object-not-found
   #:perception-object-not-in-world
   #:high-level-failure
   #:navigation-high-level-failure #:navigation-goal-in-collision
   #:looking-high-level-failure
   #:object-unreachable #:manipulation-goal-in-collision #:object-unfetchable
   #:object-undeliverable #:object-nowhere-to-be-found
   #:environment-unreachable #:environment-manipulation-impossible
   #:searching-failed #:fetching-failed #:delivering-failed
   ;; failure handling strategies
   #:retry-with-designator-solutions #:retry-with-list-solutions
   #:retry-with-loc-designator-solutions
   #:designator-next-solution #:designator-reset
   #:designator-next-different-location-solution #:next-different-location-solution
   #:*default-location-distance-threshold* #:*default-location-angle-threshold*))

(in-package :cram-common-failures)

(defun report-failure (condition stream)
  (let ((description (description condition)))
    (format stream "~a: ~a"
            (string-upcase (symbol-name (type-of condition)))
            (if (and description (not (equal description "")))
                description
                "(no description)"))))

(define-condition low-level-failure (cpl:simple-plan-failure)
  ((description :initarg :description :initform nil))
  (:report report-failure)
  (:documentation "The root of failures reported by the robot's low level
\(process modules, drivers, the projection). DESCRIPTION explains it."))

(define-condition high-level-failure (cpl:simple-plan-failure)
  ((description :initarg :description :initform nil))
  (:report report-failure)
  (:documentation "The root of failures of plans above single motions. DESCRIPTION explains it."))

(defun description (condition)
  "The text explaining CONDITION, a LOW-LEVEL-FAILURE or HIGH-LEVEL-FAILURE (or NIL). Its
:DESCRIPTION initarg is a string, or a function of no arguments that makes the string when it
is first asked for (a failure that a check catches and drops then costs no formatting)."
  (unless (typep condition '(or low-level-failure high-level-failure))
    (error "COMMON-FAIL:DESCRIPTION: ~s is not a low-level or high-level failure." condition))
  (let ((text (slot-value condition 'description)))
    (if (functionp text)
        (setf (slot-value condition 'description) (funcall text))
        text)))

;; In the task tree the class is shown next to the text, so the text is the
;; description alone.
(defmethod cram-language::failure-description ((condition low-level-failure))
  (or (description condition) ""))

(defmethod cram-language::failure-description ((condition high-level-failure))
  (or (description condition) ""))

(defmacro define-failures (&rest specs)
  "Each spec is (NAME PARENT DOC): define NAME as a subclass of PARENT."
  `(progn
     ,@(loop for (name parent doc) in specs
             collect `(define-condition ,name (,parent) ()
                        (:report report-failure)
                        (:documentation ,doc)))))

(define-failures
  (actionlib-action-timed-out low-level-failure
   "A low-level action did not finish in time.")
  (manipulation-low-level-failure low-level-failure
   "The arms or the torso could not do what they were asked.")
  (manipulation-goal-not-reached manipulation-low-level-failure
   "An arm motion ended away from its goal.")
  (manipulation-pose-unreachable manipulation-low-level-failure
   "No arm configuration reaches the requested pose (no IK solution or it collides).")
  (environment-manipulation-goal-not-reached manipulation-low-level-failure
   "Opening or closing a drawer or door ended away from its goal.")
  (torso-low-level-failure manipulation-low-level-failure
   "The torso could not do what it was asked.")
  (torso-goal-unreachable torso-low-level-failure
   "The requested torso position is outside the joint limits.")
  (torso-goal-not-reached torso-low-level-failure
   "The torso motion ended away from its goal.")
  (gripper-low-level-failure low-level-failure
   "The gripper could not do what it was asked.")
  (gripper-closed-completely gripper-low-level-failure
   "The gripper closed completely: nothing is in the hand.")
  (gripper-goal-not-reached gripper-low-level-failure
   "The gripper motion ended away from its goal.")
  (navigation-low-level-failure low-level-failure
   "The base could not do what it was asked.")
  (navigation-pose-unreachable navigation-low-level-failure
   "The requested base pose cannot be reached (e.g. it is in collision).")
  (navigation-goal-not-reached navigation-low-level-failure
   "The base motion ended away from its goal.")
  (ptu-low-level-failure low-level-failure
   "The pan-tilt unit (the neck) could not do what it was asked.")
  (ptu-goal-unreachable ptu-low-level-failure
   "The requested gaze is outside the neck's joint limits.")
  (ptu-goal-not-reached ptu-low-level-failure
   "The neck motion ended away from its goal.")
  (perception-low-level-failure low-level-failure
   "Perception could not do what it was asked.")
  (perception-object-not-in-world perception-low-level-failure
   "The object that perception was asked about does not exist in the world.")
  (navigation-high-level-failure high-level-failure
   "A plan for moving the base failed.")
  (navigation-goal-in-collision navigation-high-level-failure
   "The goal of a navigation plan is in collision.")
  (looking-high-level-failure high-level-failure
   "A plan for looking at something failed.")
  (object-unreachable high-level-failure
   "No way to reach the object was found.")
  (manipulation-goal-in-collision high-level-failure
   "The goal of a manipulation plan is in collision.")
  (object-unfetchable high-level-failure
   "The object could not be fetched.")
  (object-undeliverable high-level-failure
   "The object could not be delivered.")
  (object-nowhere-to-be-found high-level-failure
   "Searching did not find the object anywhere.")
  (environment-unreachable high-level-failure
   "A part of the environment (a drawer, a door) cannot be reached.")
  (environment-manipulation-impossible high-level-failure
   "The environment cannot be manipulated as requested.")
  (searching-failed high-level-failure
   "A search plan failed.")
  (fetching-failed high-level-failure
   "A fetch plan failed.")
  (delivering-failed high-level-failure
   "A delivery plan failed."))

(define-condition perception-object-not-found (perception-low-level-failure)
  ((object :initarg :object :initform nil :reader perception-failure-object))
  (:report (lambda (condition stream)
             (report-failure condition stream)
             (when (perception-failure-object condition)
               (format stream " (object ~a)"
                       (let ((*print-length* 10) (*print-level* 4))
                         (prin1-to-string (perception-failure-object condition)))))))
  (:documentation "Perception did not find the object it looked for; OBJECT is
the object designator (or description) it was looking for."))

(setf (documentation 'perception-failure-object 'function)
      "The object (designator) a PERCEPTION-OBJECT-NOT-FOUND failure was about.")
