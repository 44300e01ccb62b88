;;;; A private ROS master and the simulated robot (launch/sim_robot.launch) for runs and tests:
;;;; roscore on a free loopback port with its own ROS_HOME under /tmp, every process in a
;;;; process group of its own, all stopped again by STOP-PRIVATE-ROS.

(in-package :cram-ros-pms)

(defstruct private-ros
  "A private master: its directory (ROS_HOME), URI, and the processes started (newest first)."
  dir uri port (processes '()))

(defvar *private-ros* nil "The PRIVATE-ROS started by START-PRIVATE-ROS, NIL when none runs.")

(defun checkout-directory ()
  (asdf:system-source-directory "cram-plans"))

(defun free-port ()
  "A TCP port of 127.0.0.1 that nothing listens on now."
  (roslisp-utilities:free-local-port))

(defun start-group (ros name program &rest args)
  "Start PROGRAM with ARGS (SBCL makes it a process group leader), output to NAME.log in ROS's dir."
  (let ((p (sb-ext:run-program program args
                               :search t :wait nil :input nil
                               :output (format nil "~a~a.log" (private-ros-dir ros) name)
                               :if-output-exists :supersede :error :output
                               :environment (sb-ext:posix-environ))))
    (push (cons name p) (private-ros-processes ros))
    p))

(defun ros-command (program &rest args)
  "Run a ROS command line tool against the current master; its output, and whether it succeeded."
  (multiple-value-bind (out err code)
      (uiop:run-program (cons program args) :output :string :error-output :output
                                            :ignore-error-status t)
    (declare (ignore err))
    (values out (zerop code))))

(defun log-tail (ros name &optional (lines 15))
  (let ((text (ignore-errors (uiop:read-file-string (format nil "~a~a.log" (private-ros-dir ros) name)))))
    (if text
        (let ((all (uiop:split-string (string-right-trim '(#\Newline) text) :separator '(#\Newline))))
          (format nil "~{~a~^~%~}" (last all lines)))
        "(no log)")))

(defun start-private-ros (&key (timeout 30))
  "Start roscore on a free loopback port with ROS_HOME in a fresh directory under /tmp, and point
this process at it (ROS_MASTER_URI, ROS_HOME, ROS_LOG_DIR, ROS_IP). Returns the PRIVATE-ROS; an
error with roscore's log when it does not answer within TIMEOUT s."
  (when *private-ros* (stop-private-ros))
  (let* ((port (free-port))
         (dir (format nil "/tmp/cram-robot-ros-~d-~d/" (sb-posix:getpid) port))
         (ros (make-private-ros :dir dir :port port :uri (format nil "http://127.0.0.1:~d" port))))
    (ensure-directories-exist (format nil "~aros_home/log/" dir))
    (sb-posix:setenv "ROS_MASTER_URI" (private-ros-uri ros) 1)
    (sb-posix:setenv "ROS_HOME" (format nil "~aros_home" dir) 1)
    (sb-posix:setenv "ROS_LOG_DIR" (format nil "~aros_home/log" dir) 1)
    (sb-posix:setenv "ROS_IP" "127.0.0.1" 1)
    (sb-posix:unsetenv "ROS_HOSTNAME")
    (setf *private-ros* ros)
    (pushnew 'stop-private-ros sb-ext:*exit-hooks*)
    (start-group ros "roscore" "roscore" "-p" (princ-to-string port))
    (unless (loop repeat (* 5 timeout)
                  thereis (roslisp-utilities:ros-available-p :master-uri (private-ros-uri ros) :timeout 1)
                  do (sleep 0.2))
      (let ((log (log-tail ros "roscore")))
        (stop-private-ros)
        (error "roscore did not answer on port ~d within ~a s; its log:~%~a" port timeout log)))
    ros))

(defun start-sim-robot (&key (speed 1) (launch-file "launch/sim_robot.launch") arguments (timeout 60))
  "roslaunch LAUNCH-FILE (relative to the checkout) with speed:=SPEED and ARGUMENTS (strings
\"name:=value\") on the private master; returns when the node publishes /joint_states and
perception/objects, an error with the launch log after TIMEOUT s."
  (let ((ros (or *private-ros* (error "START-SIM-ROBOT: no private master; call START-PRIVATE-ROS first.")))
        (file (namestring (merge-pathnames launch-file (checkout-directory)))))
    (unless (probe-file file)
      (error "START-SIM-ROBOT: launch file ~s does not exist (~a)." launch-file file))
    (apply #'start-group ros "sim_robot" "roslaunch" file
           (format nil "speed:=~a" speed) arguments)
    (unless (loop repeat (* 3 timeout)
                  thereis (let ((topics (ros-command "rostopic" "list")))
                            (and (search "/joint_states" topics) (search "/perception/objects" topics)))
                  do (sleep 0.3))
      (error "roslaunch ~a did not bring up /joint_states and /perception/objects within ~a s; log:~%~a"
             launch-file timeout (log-tail ros "sim_robot" 25)))
    t))

(defun process-alive-p (pid)
  (ignore-errors (sb-posix:kill pid 0) t))

(defun descendants (pid)
  "PID's child processes and theirs (roslaunch puts its nodes in process groups of their own)."
  (let ((children (mapcar #'parse-integer
                          (remove "" (uiop:split-string
                                      (uiop:run-program (list "pgrep" "-P" (princ-to-string pid))
                                                        :output :string :ignore-error-status t)
                                      :separator '(#\Newline))
                                  :test #'string=))))
    (append children (mapcan #'descendants children))))

(defun stop-process-tree (process &key (grace 8))
  "SIGINT to PROCESS (roslaunch and roscore stop their nodes on it), SIGKILL to whatever of it
and its descendants is left after GRACE s."
  (let* ((pid (sb-ext:process-pid process))
         (others (descendants pid)))
    (flet ((alive () (or (sb-ext:process-alive-p process) (some #'process-alive-p others))))
      (ignore-errors (sb-posix:kill pid sb-posix:sigint))
      (loop repeat (* 10 grace) while (alive) do (sleep 0.1))
      (dolist (p (cons pid others))
        (when (process-alive-p p) (ignore-errors (sb-posix:kill p sb-posix:sigkill)))))))

(defun kill-private-master ()
  "Stop only the private roscore (the robot's nodes go on): a lost master."
  (let ((entry (assoc "roscore" (private-ros-processes *private-ros*) :test #'string=)))
    (when entry
      (let ((all (cons (sb-ext:process-pid (cdr entry)) (descendants (sb-ext:process-pid (cdr entry))))))
        (dolist (p all) (ignore-errors (sb-posix:kill p sb-posix:sigkill)))
        (loop repeat 50 while (some #'process-alive-p all) do (sleep 0.1))))))

(defun stop-private-ros ()
  "Stop every process START-PRIVATE-ROS and START-SIM-ROBOT started (nodes before the master)
and remove the private ROS_HOME."
  (let ((ros *private-ros*))
    (when ros
      (setf *private-ros* nil)
      (dolist (entry (private-ros-processes ros))
        (stop-process-tree (cdr entry))
        (ignore-errors (sb-ext:process-wait (cdr entry))))
      (ignore-errors
       (uiop:delete-directory-tree (uiop:ensure-directory-pathname (private-ros-dir ros))
                                   :validate t :if-does-not-exist :ignore))
      t)))

(defun spawn-sim-object (name type pose size)
  "Add (or move) the object NAME of TYPE at POSE (map; ((x y z) (qx qy qz qw)) or a pose) with
the bounding box SIZE (x y z) in the simulated robot's world through sim_robot/spawn; returns
when sim_robot/objects/NAME is set (10 s at most)."
  (let* ((pose (btr::ensure-pose pose "spawn pose"))
         (o (cl-transforms:origin pose)) (q (cl-transforms:orientation pose))
         (c (%make-connection :master-uri (current-master-uri)))
         (msg (roslisp:make-message "visualization_msgs/Marker"
                                    (frame_id header) "map" (stamp header) (roslisp:ros-time)
                                    ns (string-downcase (string type)) text (string-downcase (string name))
                                    type 1 action 0
                                    (x position pose) (float (cl-transforms:x o) 1d0)
                                    (y position pose) (float (cl-transforms:y o) 1d0)
                                    (z position pose) (float (cl-transforms:z o) 1d0)
                                    (x orientation pose) (float (cl-transforms:x q) 1d0)
                                    (y orientation pose) (float (cl-transforms:y q) 1d0)
                                    (z orientation pose) (float (cl-transforms:z q) 1d0)
                                    (w orientation pose) (float (cl-transforms:w q) 1d0)
                                    (x scale) (float (first size) 1d0) (y scale) (float (second size) 1d0)
                                    (z scale) (float (third size) 1d0))))
    (publish-when-connected c (robot-topic "sim_robot/spawn") "visualization_msgs/Marker" msg)
    (let ((param (robot-topic (format nil "sim_robot/objects/~(~a~)" name))))
      (or (loop repeat 100 thereis (ignore-errors (roslisp:has-param param)) do (sleep 0.1))
          (error "SPAWN-SIM-OBJECT: ~a was not set within 10 s." param)))))

(defun sim-object-position (name)
  "The position (x y z) of the object NAME in the simulated robot's world (its parameter
sim_robot/objects/NAME), or NIL."
  (let ((param (robot-topic (format nil "sim_robot/objects/~(~a~)" name))))
    (and (roslisp:has-param param)
         (subseq (coerce (roslisp:get-param param) 'list) 0 3))))

(defun sim-count (what)
  "The node's count sim_robot/counts/WHAT (e.g. \"move_base\", \"left_arm\"), 0 when unset."
  (let ((param (robot-topic (format nil "sim_robot/counts/~a" what))))
    (if (roslisp:has-param param) (roslisp:get-param param) 0)))

(defun inject-fault (spec)
  "Send the fault SPEC (a JSON text, e.g. \"{\\\"block_navigation\\\": 1}\") on sim_robot/faults."
  (let ((c (%make-connection :master-uri (current-master-uri))))
    (publish-when-connected c (robot-topic "sim_robot/faults") "std_msgs/String"
                            (roslisp:make-message "std_msgs/String" data spec))))
