;;;; The connection to the robot: subscriptions to /joint_states, /tf and perception/objects
;;;; with the latest values cached, the command publishers, and waiting with timeouts that
;;;; notice a lost master or a silent robot.

(in-package :cram-ros-pms)

(defvar *motion-timeout* 60
  "Seconds a joint motion may take at most before its goal-not-reached failure.")

(defvar *connect-timeout* 10
  "Seconds WITH-REAL-ROBOT waits for the first /joint_states and TF of the robot, and a command
publisher for its controller to connect.")

(defvar *subscribe-timeout* 60
  "Seconds a subscription may take. Subscribing to a topic nobody publishes returns at once;
it takes long only while a publisher is slow to answer (a robot's node still starting on a
loaded machine), so the wait is longer than *CONNECT-TIMEOUT*.")

(defvar *handshake-timeout* 15
  "Seconds roslisp waits for a publisher's answer to a new subscription's handshake (its
ROSLISP::*TCP-TIMEOUT*, 5 s by default, is bound to this while subscribing): a node that is
still starting on a loaded machine may take longer.")

(defvar *silence-timeout* 3
  "Seconds /joint_states (or the action status of move_base) may stay silent while a motion
waits before ROBOT-CONNECTION-ERROR.")

(defvar *master-check-interval* 1
  "Seconds between checks that the ROS master still answers while a motion waits.")

(defparameter *odometry-child-frame* "base_footprint"
  "Default base frame whose map pose comes from TF (the ROBOT-BASE-FRAME fact overrides it).")

(defun now ()
  "Seconds of the monotonic wall clock."
  (/ (get-internal-real-time) (float internal-time-units-per-second 1d0)))

(defun robot-topic (name)
  "The full ROS name of the robot interface NAME (relative, as in the contract)."
  (let ((ns (string-right-trim "/" *robot-namespace*)))
    (if (or (string= ns "") (char= (char name 0) #\/))
        (if (char= (char name 0) #\/) name (concatenate 'string "/" name))
        (concatenate 'string (if (char= (char ns 0) #\/) "" "/") ns "/" name))))

(defun current-master-uri ()
  "roslisp's master as a string http://HOST:PORT."
  (let ((uri roslisp:*master-uri*))
    (if (stringp uri) uri (format nil "http://~a:~a" (roslisp::uri-address uri) (roslisp::uri-port uri)))))

(defun connection-fail (name fmt &rest args)
  "Signal ROBOT-CONNECTION-ERROR about NAME."
  (error 'robot-connection-error :name name :reason (apply #'format nil fmt args)))

;;; ---- the connection -----------------------------------------------------------------------------

(defstruct (connection (:constructor %make-connection))
  (lock (sb-thread:make-mutex :name "robot connection"))
  (changed (sb-thread:make-waitqueue))
  (joints (make-hash-table :test 'equal))   ; joint name → position
  (joint-time 0d0)                          ; NOW of the last /joint_states
  (joint-messages 0)                        ; /joint_states messages received
  (tf (make-hash-table :test 'equal))       ; child frame → (parent . transform)
  (tf-time 0d0)
  (perception '())                          ; (stamp markers) newest first
  (publishers (make-hash-table :test 'equal))
  (master-uri nil)
  (master-checked 0d0))

(defvar *connection* nil "The connection of the running WITH-REAL-ROBOT, NIL outside.")

(defmacro with-connection-lock ((connection) &body body)
  `(sb-thread:with-recursive-lock ((connection-lock ,connection)) ,@body))

(defun notify (connection)
  (with-connection-lock (connection)
    (sb-thread:condition-broadcast (connection-changed connection))))

(defun on-joint-states (connection msg)
  (let ((names (sensor_msgs-msg:name msg))
        (positions (sensor_msgs-msg:position msg)))
    (with-connection-lock (connection)
      (loop for n across names for p across positions
            do (setf (gethash n (connection-joints connection)) (float p 1d0)))
      (setf (connection-joint-time connection) (now))
      (incf (connection-joint-messages connection))
      (sb-thread:condition-broadcast (connection-changed connection)))))

(defun transform-from-msg (tr)
  (let ((v (geometry_msgs-msg:translation tr)) (q (geometry_msgs-msg:rotation tr)))
    (cl-transforms:make-transform
     (cl-transforms:make-3d-vector (geometry_msgs-msg:x v) (geometry_msgs-msg:y v) (geometry_msgs-msg:z v))
     (cl-transforms:make-quaternion (geometry_msgs-msg:x q) (geometry_msgs-msg:y q)
                                    (geometry_msgs-msg:z q) (geometry_msgs-msg:w q)))))

(defun on-tf (connection msg)
  (let ((edges (loop for ts across (tf2_msgs-msg:transforms msg)
                     collect (list (string-left-trim "/" (geometry_msgs-msg:child_frame_id ts))
                                   (string-left-trim "/" (std_msgs-msg:frame_id (geometry_msgs-msg:header ts)))
                                   (transform-from-msg (geometry_msgs-msg:transform ts))))))
    (with-connection-lock (connection)
      (loop for (child parent transform) in edges
            do (setf (gethash child (connection-tf connection)) (cons parent transform)))
      (setf (connection-tf-time connection) (now))
      (sb-thread:condition-broadcast (connection-changed connection)))))

(defun on-perception (connection msg)
  (let* ((markers (visualization_msgs-msg:markers msg))
         (stamp (if (plusp (length markers))
                    (std_msgs-msg:stamp (visualization_msgs-msg:header (aref markers 0)))
                    (roslisp:ros-time))))
    (with-connection-lock (connection)
      (push (list stamp markers) (connection-perception connection))
      (when (> (length (connection-perception connection)) 20)
        (setf (connection-perception connection) (subseq (connection-perception connection) 0 10)))
      (sb-thread:condition-broadcast (connection-changed connection)))))

;;; ---- the master ----------------------------------------------------------------------------------

(defun check-master (connection &key force)
  "Signal ROBOT-CONNECTION-ERROR when the master does not answer (checked at most every
*MASTER-CHECK-INTERVAL* s unless FORCE)."
  (let ((time (now)))
    (when (or force (> (- time (connection-master-checked connection)) *master-check-interval*))
      (unless (roslisp-utilities:ros-available-p :master-uri (connection-master-uri connection)
                                                 :timeout (max 0.5 (min 2 *master-check-interval*)))
        (connection-fail (connection-master-uri connection)
                         "the ROS master does not answer (it was stopped, or the network is down)."))
      (setf (connection-master-checked connection) (now)))))

(defun call-with-deadline (seconds name what thunk)
  "Call THUNK (a call to the master) in a thread; ROBOT-CONNECTION-ERROR naming NAME when it
takes longer than SECONDS."
  (let* ((result nil) (error nil)
         (thread (sb-thread:make-thread
                  (lambda () (handler-case (setf result (multiple-value-list (funcall thunk)))
                               (error (e) (setf error e))))
                  :name (format nil "robot-ros ~a" what))))
    (flet ((fail (fmt &rest args)
             ;; the usual cause is a master gone: say so rather than naming the topic
             (let ((uri (current-master-uri)))
               (unless (roslisp-utilities:ros-available-p :master-uri uri :timeout 1)
                 (connection-fail uri "the ROS master does not answer (~a: ~?)." name fmt args)))
             (apply #'connection-fail name fmt args)))
      (unless (sb-thread:join-thread thread :timeout seconds :default nil)
        (when (sb-thread:thread-alive-p thread)
          (ignore-errors (sb-thread:terminate-thread thread))
          (fail "~a took longer than ~a s." what seconds)))
      (when error
        (fail "~a failed: ~a" what error)))
    (values-list result)))

;;; ---- publishers ----------------------------------------------------------------------------------

(defun publisher (connection topic type)
  "The publication of TOPIC (a full name) as TYPE, advertised on first use."
  (with-connection-lock (connection)
    (or (gethash topic (connection-publishers connection))
        (setf (gethash topic (connection-publishers connection))
              (call-with-deadline *connect-timeout* topic "advertising"
                                  (lambda () (roslisp:advertise topic type)))))))

(defun publish-when-connected (connection topic type message)
  "Publish MESSAGE on TOPIC once a subscriber is connected (waits up to *CONNECT-TIMEOUT* s,
checking the master); ROBOT-CONNECTION-ERROR naming TOPIC when nobody listens."
  (let ((pub (publisher connection topic type))
        (deadline (+ (now) *connect-timeout*)))
    (loop until (plusp (roslisp:num-subscribers pub))
          do (check-master connection)
             (when (> (now) deadline)
               (connection-fail topic "no subscriber (controller) connected within ~a s." *connect-timeout*))
             (sleep 0.02))
    (when (zerop (roslisp:publish pub message))
      (connection-fail topic "the message could not be written to any subscriber."))
    t))

;;; ---- connecting ----------------------------------------------------------------------------------

(defvar *live-connection* nil
  "The connection the subscription callbacks feed (the latest OPEN-CONNECTION), NIL when none.")

(defvar *subscriptions* (make-hash-table :test 'equal)
  "Topic → roslisp subscriber made by this system. roslisp neither closes the connections of an
unsubscribed topic nor subscribes to it again properly, so subscriptions stay for the life of
the node and feed *LIVE-CONNECTION*.")

(defun subscription-live-p (topic)
  (let ((sub (gethash topic *subscriptions*)))
    (and sub (eq roslisp::*node-status* :running)
         (eq (roslisp::subscriber-subscription sub) (gethash topic roslisp::*subscriptions*)))))

(defun ensure-subscription (topic type callback &optional (queue 5))
  "Subscribe to TOPIC once per node; CALLBACK is called with message (and runs in roslisp's
thread for the topic)."
  (unless (subscription-live-p topic)
    (setf (gethash topic *subscriptions*)
          (or (call-with-deadline *subscribe-timeout* topic "subscribing"
                                  (lambda ()
                                    (let ((roslisp::*tcp-timeout* (max roslisp::*tcp-timeout* *handshake-timeout*)))
                                      (roslisp:subscribe topic type callback :max-queue-length queue))))
              (connection-fail topic "roslisp could not subscribe (type ~a)." type))))
  (gethash topic *subscriptions*))

(defun feed (function)
  "A callback passing its message to FUNCTION with the live connection."
  (lambda (msg)
    (let ((c *live-connection*))
      (when c (funcall function c msg)))))

(defun open-connection ()
  "Make the live connection: subscriptions to the robot's state and perception (once per node),
then wait for its joint states and base pose (ROBOT-CONNECTION-ERROR after *CONNECT-TIMEOUT* s)."
  (unless (eq roslisp::*node-status* :running)
    (error 'robot-connection-error :name "the ROS node"
                                   :reason "no node runs: call (roslisp-utilities:startup-ros) first."))
  (let ((c (%make-connection :master-uri (current-master-uri))))
    (check-master c :force t)
    (setf *live-connection* c)
    (handler-bind ((error (lambda (e) (declare (ignore e)) (close-connection c))))
      (ensure-subscription "/joint_states" "sensor_msgs/JointState" (feed #'on-joint-states) 2)
      (ensure-subscription "/tf" "tf2_msgs/TFMessage" (feed #'on-tf) 50)
      (ensure-subscription "/tf_static" "tf2_msgs/TFMessage" (feed #'on-tf) 50)
      (ensure-subscription (robot-topic "perception/objects") "visualization_msgs/MarkerArray"
                           (feed #'on-perception) 5)
      (wait-until c (lambda () (plusp (connection-joint-time c)))
                  :timeout *connect-timeout* :name "/joint_states"
                  :reason "no joint states arrived")
      (wait-until c (lambda () (base-pose-from-tf c))
                  :timeout *connect-timeout* :name "/tf"
                  :reason (format nil "no transform map → ~a arrived" (base-frame-name))))
    c))

(defun close-connection (connection)
  "Stop feeding CONNECTION (the subscriptions and publications stay for the node's life)."
  (when (eq *live-connection* connection)
    (setf *live-connection* nil))
  t)

;;; ---- waiting -------------------------------------------------------------------------------------

(defun wait-until (connection predicate &key (timeout *motion-timeout*) name reason
                                             (check-joint-states t))
  "Wait until PREDICATE (called with the connection lock held) is true; returns its value.
Checks the master every *MASTER-CHECK-INTERVAL* s and that /joint_states is not silent for
*SILENCE-TIMEOUT* s (with CHECK-JOINT-STATES); after TIMEOUT s returns NIL, or signals
ROBOT-CONNECTION-ERROR naming NAME when REASON is given."
  (let ((deadline (+ (now) timeout)))
    (loop
      (let ((value (with-connection-lock (connection)
                     (or (funcall predicate)
                         (progn (sb-thread:condition-wait (connection-changed connection)
                                                          (connection-lock connection) :timeout 0.1)
                                (funcall predicate))))))
        (when value (return value)))
      (check-master connection)
      (when (and check-joint-states (plusp (connection-joint-time connection))
                 (> (- (now) (connection-joint-time connection)) *silence-timeout*))
        (connection-fail "/joint_states" "no message for ~,1f s (the robot stopped publishing)."
                         (- (now) (connection-joint-time connection))))
      (when (> (now) deadline)
        (if reason
            (connection-fail name "~a within ~a s." reason timeout)
            (return nil))))))

;;; ---- the robot's state ---------------------------------------------------------------------------

(defun robot-joint-positions (&optional (connection *connection*))
  "A fresh hash table joint name → position of the robot's latest /joint_states."
  (with-connection-lock (connection)
    (let ((copy (make-hash-table :test 'equal)))
      (maphash (lambda (k v) (setf (gethash k copy) v)) (connection-joints connection))
      copy)))

(defun base-frame-name ()
  (or (and rob-int:*robot-name*
           (urdf-proj::fact-value '?f `(rob-int:robot-base-frame ,rob-int:*robot-name* ?f)))
      *odometry-child-frame*))

(defun base-pose-from-tf (connection &optional (frame (base-frame-name)))
  "The map pose of FRAME composed from the cached TF edges, or NIL when the chain is broken."
  (with-connection-lock (connection)
    (let ((table (connection-tf connection))
          (transform (cl-transforms:make-identity-transform))
          (current frame))
      (loop repeat 20
            do (when (string= current cram-tf:*fixed-frame*)
                 (return-from base-pose-from-tf (cl-transforms:transform->pose transform)))
               (let ((edge (gethash current table)))
                 (unless edge (return nil))
                 (setf transform (cl-transforms:transform* (cdr edge) transform)
                       current (car edge)))))))

(defun robot-base-pose (&optional (connection *connection*))
  "The map pose of the robot's base frame from TF (map → odom → base), or NIL."
  (base-pose-from-tf connection))
