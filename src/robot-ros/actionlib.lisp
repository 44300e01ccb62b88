;;;; A small actionlib client over roslisp topics (Debian's cl-actionlib has only test
;;;; messages): goal, cancel, status, feedback and result of one action, with timeouts everywhere.
;;;; Written for move_base (move_base_msgs/MoveBaseAction); the message types are parameters.
;;;; CRAM's ACTIONLIB and ACTIONLIB-CLIENT packages (actionlib-api.lisp) are built on it.

(in-package :cram-ros-pms)

(defclass action-client ()
  ((name :initarg :name :reader action-client-name
         :documentation "The action's full ROS name, e.g. \"/move_base\".")
   (action-type :initarg :action-type :reader action-client-type)
   (lock :initform (sb-thread:make-mutex :name "action client") :reader action-client-lock)
   (changed :initform (sb-thread:make-waitqueue) :reader action-client-changed)
   (statuses :initform (make-hash-table :test 'equal) :reader action-client-statuses
             :documentation "goal id → (status-keyword . text), from status and result messages.")
   (results :initform (make-hash-table :test 'equal) :reader action-client-results)
   (feedback-callbacks :initform (make-hash-table :test 'equal) :reader action-client-feedback-callbacks
                       :documentation "goal id → function of the goal's feedback message.")
   (done-callbacks :initform (make-hash-table :test 'equal) :reader action-client-done-callbacks
                   :documentation "goal id → function of the terminal status and the result message.")
   (status-time :initform 0d0 :accessor action-client-status-time
                :documentation "NOW of the last status message: the server is alive.")
   (subscribers :initform '() :accessor action-client-subscribers)
   (goal-pub :initform nil :accessor action-client-goal-pub)
   (cancel-pub :initform nil :accessor action-client-cancel-pub)
   (counter :initform 0 :accessor action-client-counter))
  (:documentation "A client of one actionlib action server, made with MAKE-ACTION-CLIENT."))

(defparameter *status-codes*
  '((0 . :pending) (1 . :active) (2 . :preempted) (3 . :succeeded) (4 . :aborted)
    (5 . :rejected) (6 . :preempting) (7 . :recalling) (8 . :recalled) (9 . :lost))
  "actionlib_msgs/GoalStatus codes.")

(defparameter *terminal-statuses* '(:preempted :succeeded :aborted :rejected :recalled :lost))

(defun status-keyword (code) (or (cdr (assoc code *status-codes*)) :lost))

(defun note-status (client id status text)
  (sb-thread:with-recursive-lock ((action-client-lock client))
    (let ((old (car (gethash id (action-client-statuses client)))))
      ;; a terminal status (from the result) is never replaced by a later active one
      (unless (and (member old *terminal-statuses*) (not (member status *terminal-statuses*)))
        (setf (gethash id (action-client-statuses client)) (cons status text))))
    (sb-thread:condition-broadcast (action-client-changed client))))

(defun run-callback (client callback &rest arguments)
  "Call a user's CALLBACK with ARGUMENTS; an error in it is logged, and roslisp's thread goes on."
  (handler-case (apply callback arguments)
    (error (e)
      (cpl:log-message :warn '(actionlib callback) "~a: a callback signalled ~a: ~a"
                       (action-client-name client) (type-of e) e))))

(defun on-status (client msg)
  (loop for st across (actionlib_msgs-msg:status_list msg)
        for id = (actionlib_msgs-msg:id (actionlib_msgs-msg:goal_id st))
        when (gethash id (action-client-statuses client))
          do (note-status client id (status-keyword (actionlib_msgs-msg:status st))
                          (actionlib_msgs-msg:text st)))
  (sb-thread:with-recursive-lock ((action-client-lock client))
    (setf (action-client-status-time client) (now))
    (sb-thread:condition-broadcast (action-client-changed client))))

(defun message-field (msg name)
  "The field NAME (a string such as \"STATUS\") of the ROS message MSG."
  (funcall (find-symbol name (symbol-package (class-name (class-of msg)))) msg))

(defun on-result (client msg)
  "Record the result of one of CLIENT's goals and its terminal status, then call the goal's done
callback (with the status and the result message): a goal is done when its result came."
  (let* ((st (message-field msg "STATUS"))
         (id (actionlib_msgs-msg:id (actionlib_msgs-msg:goal_id st)))
         (status (status-keyword (actionlib_msgs-msg:status st)))
         (done nil))
    (when (sb-thread:with-recursive-lock ((action-client-lock client))
            (when (gethash id (action-client-statuses client))
              (setf (gethash id (action-client-results client)) msg)
              (setf (action-client-status-time client) (now))
              (setf done (gethash id (action-client-done-callbacks client)))
              (remhash id (action-client-done-callbacks client))
              (remhash id (action-client-feedback-callbacks client))
              t))
      (note-status client id status (actionlib_msgs-msg:text st))
      (when done (run-callback client done status msg)))))

(defun on-feedback (client msg)
  "Pass the feedback of one of CLIENT's goals to that goal's feedback callback."
  (let* ((st (message-field msg "STATUS"))
         (id (actionlib_msgs-msg:id (actionlib_msgs-msg:goal_id st)))
         (callback (sb-thread:with-recursive-lock ((action-client-lock client))
                     (gethash id (action-client-feedback-callbacks client)))))
    (when callback
      (run-callback client callback (message-field msg "FEEDBACK")))))

(defun make-action-client (name action-type &key (timeout *connect-timeout*))
  "A client of the action NAME (a full ROS name, e.g. \"/move_base\") of ACTION-TYPE (e.g.
\"move_base_msgs/MoveBase\"): subscribes to NAME/status, NAME/result and NAME/feedback,
advertises NAME/goal and NAME/cancel, and waits up to TIMEOUT s for the server (its first status
message and its subscription to the goal topic); ROBOT-CONNECTION-ERROR naming the action
otherwise. TIMEOUT NIL does not wait (see SERVER-CONNECTED-P)."
  (let ((client (make-instance 'action-client :name name :action-type action-type)))
    (handler-bind ((error (lambda (e) (declare (ignore e)) (ignore-errors (close-action-client client)))))
      (flet ((sub (suffix type fn)
               (let ((topic (format nil "~a/~a" name suffix)))
                 (remhash topic *subscriptions*)
                 (push (ensure-subscription topic type (lambda (m) (funcall fn client m)) 10)
                       (action-client-subscribers client))))
             (pub (suffix type)
               (let ((topic (format nil "~a/~a" name suffix)))
                 (call-with-deadline timeout topic "advertising" (lambda () (roslisp:advertise topic type))))))
        (sub "status" "actionlib_msgs/GoalStatusArray" #'on-status)
        (sub "result" (format nil "~aActionResult" action-type) #'on-result)
        (sub "feedback" (format nil "~aActionFeedback" action-type) #'on-feedback)
        (setf (action-client-goal-pub client) (pub "goal" (format nil "~aActionGoal" action-type))
              (action-client-cancel-pub client) (pub "cancel" "actionlib_msgs/GoalID"))
        (let ((deadline (and timeout (+ (now) timeout))))
          (loop until (or (null deadline) (server-connected-p client))
                do (when (> (now) deadline)
                     (connection-fail name "the action server did not answer within ~a s (no ~
                                            status message, or it does not subscribe to ~a/goal)."
                                      timeout name))
                   (sleep 0.02)))))
    client))

(defun server-connected-p (client)
  "True when CLIENT's server has sent a status message and listens to its goal and cancel topics."
  (and (plusp (action-client-status-time client))
       (plusp (roslisp:num-subscribers (action-client-goal-pub client)))
       (plusp (roslisp:num-subscribers (action-client-cancel-pub client)))))

(defun close-action-client (client)
  "Forget CLIENT's topics (roslisp keeps its connections for the node's life, see *SUBSCRIPTIONS*)."
  (setf (action-client-subscribers client) '())
  t)

(defun send-goal (client goal &key feedback-cb done-cb)
  "Send GOAL (a message of the action's Goal type) to CLIENT's server; returns the goal id.
FEEDBACK-CB is called with each feedback message of the goal, DONE-CB with its terminal status
and result message (in roslisp's threads)."
  (let* ((stamp (roslisp:ros-time))
         (id (format nil "~a-~d-~,3f" (string-left-trim "/" roslisp::*ros-node-name*)
                     (incf (action-client-counter client)) stamp))
         (type (format nil "~aActionGoal" (action-client-type client)))
         (msg (roslisp:make-message type
                                    (stamp header) stamp
                                    (stamp goal_id) stamp
                                    (id goal_id) id
                                    goal goal)))
    (sb-thread:with-recursive-lock ((action-client-lock client))
      (setf (gethash id (action-client-statuses client)) (cons :pending ""))
      (when feedback-cb (setf (gethash id (action-client-feedback-callbacks client)) feedback-cb))
      (when done-cb (setf (gethash id (action-client-done-callbacks client)) done-cb)))
    (when (zerop (roslisp:publish (action-client-goal-pub client) msg))
      (connection-fail (action-client-name client) "the goal could not be sent (no server connected)."))
    id))

(defun cancel-goal (client id)
  "Ask CLIENT's server to cancel the goal ID (does not wait)."
  (ignore-errors
   (roslisp:publish (action-client-cancel-pub client)
                    (roslisp:make-message "actionlib_msgs/GoalID" stamp (roslisp:ros-time) id id)))
  t)

(defun wait-for-result (client id &key (timeout 60) (silence *silence-timeout*) connection)
  "Wait until the goal ID reaches a terminal status; returns it (:SUCCEEDED, :ABORTED,
:PREEMPTED, :REJECTED, :RECALLED) and the status text, or :TIMEOUT after TIMEOUT s (the goal is
then cancelled). ROBOT-CONNECTION-ERROR naming the action when the server sends no status for
SILENCE s; with CONNECTION, also when its master stops answering."
  (let ((deadline (+ (now) timeout)))
    (loop
      (let ((entry (sb-thread:with-recursive-lock ((action-client-lock client))
                     (let ((e (gethash id (action-client-statuses client))))
                       (if (member (car e) *terminal-statuses*)
                           e
                           (progn (sb-thread:condition-wait (action-client-changed client)
                                                            (action-client-lock client) :timeout 0.1)
                                  nil))))))
        (when entry
          (return (values (car entry) (cdr entry)))))
      (when connection (check-master connection))
      (when (> (- (now) (action-client-status-time client)) silence)
        (cancel-goal client id)
        (connection-fail (action-client-name client) "the action server sent no status for ~,1f s."
                         (- (now) (action-client-status-time client))))
      (when (> (now) deadline)
        (cancel-goal client id)
        (return (values :timeout (format nil "no result within ~a s" timeout)))))))

(setf (documentation 'action-client-name 'function)
      "The full ROS name of the action an ACTION-CLIENT talks to, e.g. \"/move_base\".")
