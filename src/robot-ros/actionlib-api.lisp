;;;; CRAM's actionlib client API (roslisp_common's ACTIONLIB package) over the action client of
;;;; the robot process modules (actionlib.lisp): clients made by action name and type, goals
;;;; sent with feedback and done callbacks, goal handles with their states, CALL-GOAL.

(defpackage :actionlib
  (:use :cl)
  (:export #:*action-server-timeout* #:server-lost #:server-lost-action
           #:action-client #:make-action-client #:wait-for-server #:connected-to-server
           #:make-action-goal #:send-goal #:cancel-goal #:wait-for-result #:call-goal
           #:goal-handle #:goal-id #:goal-state #:goal-status-text #:result
           #:terminal-state-p #:+goal-states+)
  (:documentation "CRAM's actionlib client (roslisp_common): MAKE-ACTION-CLIENT, WAIT-FOR-SERVER,
SEND-GOAL, WAIT-FOR-RESULT, CALL-GOAL, CANCEL-GOAL, goal states and feedback callbacks. Loaded
with the system cram-plans/cram-ros-pms."))

(in-package :actionlib)

(defvar *action-server-timeout* 10
  "Seconds CALL-GOAL waits for the action server, and the silence (no status message) after
which a goal's server counts as lost (SERVER-LOST).")

(defparameter +goal-states+ '(:pending :active :preempted :succeeded :aborted :rejected
                             :preempting :recalling :recalled :lost)
  "The states of a goal, after actionlib_msgs/GoalStatus; GOAL-STATE returns one of them.")

(define-condition server-lost (error)
  ((action :initarg :action :reader server-lost-action)
   (reason :initarg :reason :reader server-lost-reason))
  (:report (lambda (condition stream)
             (format stream "Action server ~a lost: ~a" (server-lost-action condition)
                     (server-lost-reason condition))))
  (:documentation "The action server did not answer in time, or stopped answering."))

(setf (documentation 'server-lost-action 'function)
      "The ROS name of the action a SERVER-LOST error is about.")

(defclass action-client ()
  ((transport :initarg :transport :reader transport)
   (goal-type :initarg :goal-type :reader goal-type))
  (:documentation "A client of one actionlib action server, made with MAKE-ACTION-CLIENT."))

(defmethod print-object ((client action-client) stream)
  (print-unreadable-object (client stream :type t)
    (format stream "~a" (cram-ros-pms:action-client-name (transport client)))))

(defstruct (goal-handle (:constructor make-goal-handle (client goal-id)) (:copier nil))
  "A goal sent with SEND-GOAL: its client and id."
  (client nil :read-only t)
  (goal-id nil :read-only t))

(setf (documentation 'goal-handle-goal-id 'function) "The actionlib goal id of a GOAL-HANDLE.")

(defun goal-id (goal-handle)
  "The actionlib goal id (a string) of GOAL-HANDLE."
  (goal-handle-goal-id (check-goal-handle goal-handle 'goal-id)))

(defun check-goal-handle (object operation)
  (unless (goal-handle-p object)
    (error "~a: ~s is not a goal handle; expected what ACTIONLIB:SEND-GOAL returns." operation object))
  object)

(defun check-client (object operation)
  (unless (typep object 'action-client)
    (error "~a: ~s is not an action client; expected what ACTIONLIB:MAKE-ACTION-CLIENT returns."
           operation object))
  object)

(defun check-seconds (value what operation)
  (unless (or (null value) (and (realp value) (>= value 0)))
    (error "~a: ~a ~s, expected NIL or a non-negative number of seconds." operation what value))
  value)

(defun action-base-type (action-type)
  "ACTION-TYPE (\"pkg/NameAction\" or \"pkg/Name\") as \"pkg/Name\"."
  (unless (and (stringp action-type) (find #\/ action-type)
               (< 0 (position #\/ action-type) (1- (length action-type))))
    (error "MAKE-ACTION-CLIENT: action type ~s, expected a string such as ~
            \"actionlib/TestAction\" or \"move_base_msgs/MoveBaseAction\"." action-type))
  (if (and (> (length action-type) 6) (string= "Action" action-type :start2 (- (length action-type) 6)))
      (subseq action-type 0 (- (length action-type) 6))
      action-type))

(defun make-action-client (action-name action-type)
  "A client of the action ACTION-NAME (e.g. \"/my_gripper/command\") of ACTION-TYPE (e.g.
\"actionlib/TestAction\"); needs a running node. It does not wait for the server: see
WAIT-FOR-SERVER. Unknown message types are an error naming them."
  (unless (and (stringp action-name) (plusp (length action-name)))
    (error "MAKE-ACTION-CLIENT: action name ~s, expected a ROS name string such as \"/move_base\"."
           action-name))
  (unless (eq roslisp::*node-status* :running)
    (error "MAKE-ACTION-CLIENT ~a: no ROS node runs; start one first ~
            (roslisp:start-ros-node or roslisp-utilities:startup-ros)." action-name))
  (let* ((base (action-base-type action-type))
         (goal-type (format nil "~aGoal" base)))
    (handler-case (roslisp:make-message goal-type)
      (error ()
        (error "MAKE-ACTION-CLIENT: ~s names no loaded message type ~a (load its message system, ~
                e.g. \"actionlib-msg\" for actionlib/TestAction)." action-type goal-type)))
    (make-instance 'action-client
                   :transport (cram-ros-pms:make-action-client
                               (if (char= (char action-name 0) #\/) action-name
                                   (concatenate 'string "/" action-name))
                               base :timeout nil)
                   :goal-type goal-type)))

(defun connected-to-server (client)
  "True when CLIENT's action server answers (it sent a status and listens to the goal topic)."
  (cram-ros-pms::server-connected-p (transport (check-client client 'connected-to-server))))

(defun wait-for-server (client &optional timeout)
  "Wait until CLIENT's server answers, at most TIMEOUT seconds (NIL: no limit); true when it does."
  (check-client client 'wait-for-server)
  (check-seconds timeout "timeout" 'wait-for-server)
  (let ((deadline (and timeout (+ (cram-ros-pms::now) timeout))))
    (loop until (connected-to-server client)
          do (when (and deadline (> (cram-ros-pms::now) deadline))
               (return-from wait-for-server nil))
             (sleep 0.02))
    t))

(defmacro make-action-goal (client &rest fields)
  "A goal message for CLIENT's action, with FIELDS given as in ROSLISP:MAKE-MESSAGE (slot names
unevaluated, values evaluated), e.g. (make-action-goal client goal 40)."
  `(roslisp:make-message (goal-type (check-client ,client 'make-action-goal)) ,@fields))

(defun send-goal (client goal &key feedback-cb done-cb)
  "Send GOAL (a message of the action's Goal type) to CLIENT's server; returns a GOAL-HANDLE.
FEEDBACK-CB is called with each feedback message of the goal, DONE-CB with the goal's terminal
state (a keyword of +GOAL-STATES+) and its result message (NIL when none came); both run in
roslisp's threads."
  (check-client client 'send-goal)
  (dolist (callback (list feedback-cb done-cb))
    (unless (or (null callback) (functionp callback) (and (symbolp callback) (fboundp callback)))
      (error "SEND-GOAL: callback ~s, expected NIL or a function." callback)))
  (unless (typep goal 'roslisp-msg-protocol:ros-message)
    (error "SEND-GOAL: goal ~s, expected a ~a message (ACTIONLIB:MAKE-ACTION-GOAL makes one)."
           goal (goal-type client)))
  (make-goal-handle
   client
   (cram-ros-pms:send-goal (transport client) goal
                           :feedback-cb feedback-cb
                           :done-cb (and done-cb
                                         (lambda (status result-message)
                                           (funcall done-cb status
                                                    (and result-message
                                                         (cram-ros-pms::message-field
                                                          result-message "RESULT"))))))))

(defun goal-entry (goal-handle)
  (let ((transport (transport (goal-handle-client goal-handle))))
    (sb-thread:with-recursive-lock ((cram-ros-pms::action-client-lock transport))
      (gethash (goal-handle-goal-id goal-handle) (cram-ros-pms::action-client-statuses transport)))))

(defun goal-state (goal-handle)
  "The state of the goal, a keyword of +GOAL-STATES+."
  (car (goal-entry (check-goal-handle goal-handle 'goal-state))))

(defun goal-status-text (goal-handle)
  "The text the server gave with the goal's latest status."
  (cdr (goal-entry (check-goal-handle goal-handle 'goal-status-text))))

(defun terminal-state-p (state)
  "True for the states a goal ends in: :SUCCEEDED, :ABORTED, :PREEMPTED, :REJECTED, :RECALLED, :LOST."
  (and (member state cram-ros-pms::*terminal-statuses*) t))

(defun result-message (goal-handle)
  "The ActionResult message of the goal, NIL while none came."
  (let ((transport (transport (goal-handle-client goal-handle))))
    (sb-thread:with-recursive-lock ((cram-ros-pms::action-client-lock transport))
      (gethash (goal-handle-goal-id goal-handle) (cram-ros-pms::action-client-results transport)))))

(defun result (goal-handle)
  "The result message of the goal (the action's Result type), NIL before it ended."
  (let ((message (result-message (check-goal-handle goal-handle 'result))))
    (and message (cram-ros-pms::message-field message "RESULT"))))

(defun cancel-goal (goal-handle)
  "Ask the server to cancel the goal (does not wait; its state becomes :PREEMPTED or :RECALLED)."
  (check-goal-handle goal-handle 'cancel-goal)
  (cram-ros-pms:cancel-goal (transport (goal-handle-client goal-handle)) (goal-handle-goal-id goal-handle)))

(defun wait-for-result (goal-handle &optional timeout)
  "Wait until the goal ends, at most TIMEOUT seconds (NIL: as long as the server answers); true
when it ended, NIL on timeout (the goal is then cancelled). SERVER-LOST when the server sends no
status for *ACTION-SERVER-TIMEOUT* seconds."
  (check-goal-handle goal-handle 'wait-for-result)
  (check-seconds timeout "timeout" 'wait-for-result)
  (let ((transport (transport (goal-handle-client goal-handle))))
    (handler-case
        (and (not (eq :timeout (cram-ros-pms:wait-for-result
                                transport (goal-handle-goal-id goal-handle)
                                :timeout (or timeout most-positive-fixnum)
                                :silence *action-server-timeout*)))
             ;; the terminal status may come before the result message: wait for that too
             (or (result-message goal-handle)
                 (loop with deadline = (+ (cram-ros-pms::now) *action-server-timeout*)
                       do (sleep 0.01)
                       thereis (result-message goal-handle)
                       until (> (cram-ros-pms::now) deadline))
                 (error 'server-lost :action (cram-ros-pms:action-client-name transport)
                                     :reason "the goal ended without a result message."))
             t)
      (cram-ros-pms:robot-connection-error (e)
        (error 'server-lost :action (cram-ros-pms:action-client-name transport)
                            :reason (cram-ros-pms:robot-connection-error-reason e))))))

(defun call-goal (client goal &key timeout feedback-cb)
  "Send GOAL to CLIENT's server (waiting for the server at most *ACTION-SERVER-TIMEOUT* s, else
SERVER-LOST) and wait for its end, at most TIMEOUT seconds (NIL: no limit; a goal still running
then is cancelled). Returns the result message (NIL after a timeout), the terminal state (or
:TIMEOUT) and the goal handle. FEEDBACK-CB as for SEND-GOAL."
  (check-client client 'call-goal)
  (check-seconds timeout "timeout" 'call-goal)
  (unless (wait-for-server client *action-server-timeout*)
    (error 'server-lost :action (cram-ros-pms:action-client-name (transport client))
                        :reason (format nil "no answer within ~a s (*action-server-timeout*)."
                                        *action-server-timeout*)))
  (let ((handle (send-goal client goal :feedback-cb feedback-cb)))
    (if (wait-for-result handle timeout)
        (values (result handle) (goal-state handle) handle)
        (values nil :timeout handle))))
