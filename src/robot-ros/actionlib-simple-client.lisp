;;;; CRAM's ACTIONLIB-CLIENT package: action clients registered under a symbol, made on their
;;;; first call and kept for the node's life, as CRAM's process modules use them.

(defpackage :actionlib-client
  (:use :cl)
  (:export #:make-simple-action-client #:call-simple-action-client #:get-simple-action-client
           #:destroy-simple-action-clients)
  (:documentation "CRAM's simple action clients: (make-simple-action-client 'gripper
\"/my_gripper/command\" \"actionlib/TestAction\" 10), then (call-simple-action-client 'gripper
:action-goal goal). Built on the ACTIONLIB package."))

(in-package :actionlib-client)

(defstruct (simple-client (:copier nil))
  ros-name ros-type timeout (client nil))

(defvar *simple-clients* (make-hash-table :test 'eq)
  "Symbol → SIMPLE-CLIENT, registered by MAKE-SIMPLE-ACTION-CLIENT.")

(defun make-simple-action-client (name ros-name ros-type timeout &key initialize-now)
  "Register the action client NAME (a symbol) of the action ROS-NAME (e.g.
\"/my_gripper/command\") of ROS-TYPE (e.g. \"actionlib/TestAction\"), whose goals may take
TIMEOUT seconds. With INITIALIZE-NOW the client is made and waits for its server now, else on
its first call. Returns NAME."
  (unless (and (symbolp name) name)
    (error "MAKE-SIMPLE-ACTION-CLIENT: name ~s, expected a non-NIL symbol such as 'gripper." name))
  (unless (and (stringp ros-name) (plusp (length ros-name)))
    (error "MAKE-SIMPLE-ACTION-CLIENT ~s: ROS name ~s, expected a string such as \"/move_base\"."
           name ros-name))
  (unless (stringp ros-type)
    (error "MAKE-SIMPLE-ACTION-CLIENT ~s: ROS type ~s, expected a string such as ~
            \"actionlib/TestAction\"." name ros-type))
  (unless (and (realp timeout) (plusp timeout))
    (error "MAKE-SIMPLE-ACTION-CLIENT ~s: timeout ~s, expected a positive number of seconds."
           name timeout))
  (setf (gethash name *simple-clients*)
        (make-simple-client :ros-name ros-name :ros-type ros-type :timeout timeout))
  (when initialize-now (get-simple-action-client name))
  name)

(defun get-simple-action-client (name)
  "The ACTIONLIB:ACTION-CLIENT registered as NAME, made (and waited for, at most
ACTIONLIB:*ACTION-SERVER-TIMEOUT* s, else ACTIONLIB:SERVER-LOST) on first use."
  (let ((entry (or (gethash name *simple-clients*)
                   (error "No simple action client ~s; register it with ~
                           ACTIONLIB-CLIENT:MAKE-SIMPLE-ACTION-CLIENT (registered: ~
                           ~:[none~;~:*~{~s~^, ~}~])."
                          name (loop for key being the hash-keys of *simple-clients* collect key)))))
    (or (simple-client-client entry)
        (let ((client (actionlib:make-action-client (simple-client-ros-name entry)
                                                    (simple-client-ros-type entry))))
          (unless (actionlib:wait-for-server client actionlib:*action-server-timeout*)
            (error 'actionlib:server-lost
                   :action (simple-client-ros-name entry)
                   :reason (format nil "no answer within ~a s (actionlib:*action-server-timeout*)."
                                   actionlib:*action-server-timeout*)))
          (setf (simple-client-client entry) client)))))

(defun call-simple-action-client (name &key action-goal action-timeout feedback-cb)
  "Send ACTION-GOAL (a goal message, e.g. from ACTIONLIB:MAKE-ACTION-GOAL) with the client NAME
and wait for its end, at most ACTION-TIMEOUT seconds (default: the client's timeout). Returns
the result message and the terminal state (or :TIMEOUT), as ACTIONLIB:CALL-GOAL."
  (let ((client (get-simple-action-client name))
        (timeout (or action-timeout (simple-client-timeout (gethash name *simple-clients*)))))
    (unless action-goal
      (error "CALL-SIMPLE-ACTION-CLIENT ~s: no :action-goal given." name))
    (multiple-value-bind (result state)
        (actionlib:call-goal client action-goal :timeout timeout :feedback-cb feedback-cb)
      (values result state))))

(defun destroy-simple-action-clients ()
  "Forget every registered simple action client (a new node needs new clients)."
  (clrhash *simple-clients*)
  t)

(roslisp-utilities:register-ros-cleanup-function destroy-simple-action-clients)
