;;;; Tests of the ROS integration against a private roscore: a master on a free loopback port with
;;;; its own ROS_HOME, the launch files, STARTUP-ROS building the belief state from the parameter
;;;; server, its TF and markers seen by other nodes, and a clean stop of everything started.

(in-package :cram-plans-tests-ros)

(in-suite ros)

(defstruct private-ros
  (dir nil) (uri nil) (env '()) (processes '()) (log '()))

(defvar *ros* nil "The PRIVATE-ROS of the running live test.")

(defun note (fmt &rest args)
  (push (apply #'format nil fmt args) (private-ros-log *ros*)))

(defun executable (name)
  "The path of the executable NAME in /usr/bin or on PATH; an error saying what is missing."
  (or (loop for dir in (cons "/usr/bin" (uiop:split-string (or (uiop:getenv "PATH") "") :separator ":"))
            for path = (and (plusp (length dir)) (probe-file (format nil "~a/~a" dir name)))
            when path return (namestring path))
      (error "~a is not installed (not in /usr/bin nor on PATH): the ROS tests need Debian's ROS ~
              packages; install them with `make setup`" name)))

(defun child-environment (uri dir)
  "The environment of the ROS processes: the private master and ROS_HOME, Debian's python3 first."
  (let ((own '("ROS_MASTER_URI" "ROS_HOME" "ROS_LOG_DIR" "ROS_IP" "ROS_HOSTNAME" "PATH")))
    (append (list (format nil "ROS_MASTER_URI=~a" uri)
                  (format nil "ROS_HOME=~aros_home" dir)
                  (format nil "ROS_LOG_DIR=~aros_home/log" dir)
                  "ROS_IP=127.0.0.1"
                  (format nil "PATH=/usr/bin:/bin:/usr/sbin:/sbin:~a" (or (uiop:getenv "PATH") "")))
            (remove-if (lambda (e) (some (lambda (v) (uiop:string-prefix-p (format nil "~a=" v) e)) own))
                       (sb-ext:posix-environ)))))

(defun start-ros-process (name program &rest args)
  "Start PROGRAM with ARGS in its own process group, output to NAME.log in the test directory."
  (let ((p (sb-ext:run-program (executable program) args
                               :wait nil :input nil
                               :environment (private-ros-env *ros*)
                               :output (format nil "~a~a.log" (private-ros-dir *ros*) name)
                               :if-output-exists :supersede :error :output)))
    (push p (private-ros-processes *ros*))
    p))

(defun process-log (name)
  (let ((path (format nil "~a~a.log" (private-ros-dir *ros*) name)))
    (if (probe-file path) (uiop:read-file-string path) "")))

(defun live-process-p (pid)
  "True when PID runs and is no zombie."
  (let ((stat (ignore-errors (uiop:read-file-string (format nil "/proc/~d/stat" pid)))))
    (and stat (let ((close (position #\) stat :from-end t)))
                (and close (< (+ close 2) (length stat)) (char/= #\Z (char stat (+ close 2))))))))

(defun pgrep (&rest args)
  "The live processes pgrep ARGS lists."
  (let ((out (uiop:run-program (cons "pgrep" args) :output :string :ignore-error-status t)))
    (loop for line in (uiop:split-string out :separator '(#\Newline))
          for pid = (ignore-errors (parse-integer line))
          when (and pid (live-process-p pid)) collect pid)))

(defun group-members (pgid)
  "The live processes of the process group PGID."
  (pgrep "-g" (princ-to-string pgid)))

(defun processes-under (dir)
  "Live processes whose command line mentions DIR (the nodes' __log:= arguments do)."
  (pgrep "-f" (namestring dir)))

(defun wait-until (seconds predicate &optional (step 0.1))
  "True as soon as PREDICATE is; NIL after SECONDS."
  (let ((end (+ (get-internal-real-time) (* seconds internal-time-units-per-second))))
    (loop (when (funcall predicate) (return t))
          (when (> (get-internal-real-time) end) (return nil))
          (sleep step))))

(defun stop-process (p)
  "SIGINT to P's process group, then SIGTERM, then SIGKILL, until none of it is left."
  (let ((pgid (sb-ext:process-pid p)))
    (loop for (signal seconds) in (list (list sb-posix:sigint 10) (list sb-posix:sigterm 3)
                                        (list sb-posix:sigkill 2))
          while (group-members pgid)
          do (ignore-errors (sb-posix:kill (- pgid) signal))
             (wait-until seconds (lambda () (null (group-members pgid))) 0.1))
    (ignore-errors (sb-ext:process-wait p))
    (sb-ext:process-close p)))

(defun run-with-timeout (seconds program &rest args)
  "Run PROGRAM with ARGS in the ROS environment; (values exit-code output), exit code NIL when it
had to be killed after SECONDS."
  (let* ((name (format nil "run-~a-~d" (file-namestring program) (get-internal-real-time)))
         (p (apply #'start-ros-process name program args)))
    (let ((done (wait-until seconds (lambda () (not (sb-ext:process-alive-p p))) 0.05)))
      (unless done (stop-process p))
      (setf (private-ros-processes *ros*) (remove p (private-ros-processes *ros*)))
      (values (and done (sb-ext:process-exit-code p)) (process-log name)))))

(defun rosparam-list ()
  (multiple-value-bind (code out) (run-with-timeout 10 "rosparam" "list")
    (and (eql code 0) (uiop:split-string (string-trim '(#\Newline) out) :separator '(#\Newline)))))

(defun start-roscore ()
  (let ((port (free-port)))
    (setf (private-ros-uri *ros*) (format nil "http://127.0.0.1:~d" port)
          (private-ros-env *ros*) (child-environment (private-ros-uri *ros*) (private-ros-dir *ros*)))
    (let ((p (start-ros-process "roscore" "roscore" "-p" (princ-to-string port))))
      (unless (wait-until 30 (lambda () (and (sb-ext:process-alive-p p) (rosparam-list))) 0.2)
        (error "roscore did not answer on ~a within 30 s; its log:~%~a"
               (private-ros-uri *ros*) (process-log "roscore"))))))

(defun roslaunch (name file &rest args)
  "roslaunch FILE (relative to the repository) with ARGS; waits until the map server runs."
  (let ((p (apply #'start-ros-process name "roslaunch" (namestring (repo-file file)) args)))
    (unless (wait-until 30 (lambda ()
                             (and (sb-ext:process-alive-p p)
                                  (member "/map_server" (rosnode-list) :test #'string=)))
                        0.2)
      (error "roslaunch ~a did not bring up /map_server within 30 s; its log:~%~a" file (process-log name)))
    p))

(defun rosnode-list ()
  (multiple-value-bind (code out) (run-with-timeout 10 "rosnode" "list")
    (and (eql code 0) (uiop:split-string (string-trim '(#\Newline) out) :separator '(#\Newline)))))

(defun tf-frames (&rest args)
  "Run tools/ros/tf_frames.py with ARGS; (values exit-code output)."
  (apply #'run-with-timeout 20 "python3" (namestring (repo-file "tools/ros/tf_frames.py")) args))

(defun call-with-private-ros (thunk)
  "Call THUNK with *ROS* a private master (its own port, directory and ROS_HOME, our process's
ROS variables pointing at it), then stop every process started and remove the directory.
Returns the live processes left behind (NIL when the cleanup was complete)."
  (let* ((dir (uiop:ensure-directory-pathname
               (format nil "/tmp/cram-ros-test-~d-~d" (sb-posix:getpid) (get-universal-time))))
         (*ros* (make-private-ros :dir (namestring dir))))
    (ensure-directories-exist (merge-pathnames "ros_home/log/" dir))
    (with-env (("ROS_HOME" (format nil "~aros_home" (namestring dir)))
               ("ROS_LOG_DIR" (format nil "~aros_home/log" (namestring dir)))
               ("ROS_IP" "127.0.0.1") ("ROS_HOSTNAME" nil) ("ROS_MASTER_URI" nil))
      (unwind-protect
           (progn (start-roscore)
                  (sb-posix:setenv "ROS_MASTER_URI" (private-ros-uri *ros*) 1)
                  (funcall thunk))
        (ignore-errors (roslisp-utilities:shutdown-ros))
        (mapc #'stop-process (private-ros-processes *ros*))))
    ;; a node killed with its group may take a moment to go under load
    (wait-until 10 (lambda () (null (processes-under dir))) 0.2)
    (let ((left (processes-under dir)))
      (dolist (pid left) (ignore-errors (sb-posix:kill pid sb-posix:sigkill)))
      (uiop:delete-directory-tree dir :validate t :if-does-not-exist :ignore)
      left)))

;;; ---- the belief state built from the parameter server -------------------------------------------

(defvar *spawned-from* '() "Where the init function took the URDFs from.")

(defun spawn-world-from-parameters (environment-parameter environment-name robot-name)
  "Make a fresh current world: floor, the environment URDF from ENVIRONMENT-PARAMETER, the robot
from robot_description, a red bottle."
  (multiple-value-bind (env-urdf env-source)
      (roslisp-utilities:robot-description-string :parameter environment-parameter)
    (multiple-value-bind (robot-urdf robot-source) (roslisp-utilities:robot-description-string)
      (let ((w (make-instance 'btr:bt-reasoning-world)))
        (btr:add-object w :static-plane :floor '((0 0 0) (0 0 0 1)))
        (btr:add-object w :urdf environment-name '((0 0 0) (0 0 0 1)) :urdf env-urdf
                        :collision-group :static-filter :collision-mask '(:default-filter))
        (btr:add-object w :urdf robot-name '((0 0 0) (0 0 0 1)) :urdf robot-urdf)
        (btr:add-object w :mesh :bottle-1 '((-2 -0.9 0.86) (0 0 0 1)) :mesh :bottle :color '(1 0 0))
        (setf *spawned-from* (list env-source robot-source)
              btr:*current-bullet-world* w)))))

(defun init-kitchen-world () (spawn-world-from-parameters "kitchen_description" :iai-kitchen :pr2))
(defun init-shop-world () (spawn-world-from-parameters "shelf_description" :dm-shelves :pepper))

(defun subscribe-collecting (topic type)
  "Subscribe to TOPIC; returns a function giving the messages received so far (newest first)."
  (let ((messages '()) (lock (bt:make-lock "collected")))
    (roslisp:subscribe topic type (lambda (m) (bt:with-lock-held (lock) (push m messages))))
    (lambda () (bt:with-lock-held (lock) (copy-list messages)))))

(defun tf-x-of (messages child)
  "The x translation of the newest transform to CHILD among the TF MESSAGES, or NIL."
  (dolist (m messages)
    (let ((tr (find child (tf2_msgs-msg:transforms m) :key #'geometry_msgs-msg:child_frame_id
                                                        :test #'string=)))
      (when tr
        (return (geometry_msgs-msg:x (geometry_msgs-msg:translation (geometry_msgs-msg:transform tr))))))))

(defun check-kitchen-world ()
  (let ((params (rosparam-list)))
    (is (member "/robot_description" params :test #'string=))
    (is (member "/kitchen_description" params :test #'string=)))
  (let ((roslisp-utilities:*ros-init-functions* '(init-kitchen-world)))
    (is (search "cram_plans" (roslisp-utilities:startup-ros :publish-rate 20))))
  (is-true (roslisp-utilities:ros-running-p))
  (is-true (roslisp-utilities:belief-state-publisher-running-p))
  (is (equal '("/kitchen_description" "/robot_description") *spawned-from*))
  (is (string= (uiop:read-file-string (repo-file "robots/pr2/pr2.urdf"))
               (roslisp-utilities:robot-description-string)))
  (let ((pr2 (btr:object btr:*current-bullet-world* :pr2)))
    (is (typep pr2 'btr:robot-object))
    (is (btr:link-exists-p pr2 "l_gripper_tool_frame")))
  ;; another process sees the belief state's TF: map → l_gripper_tool_frame is connected
  (multiple-value-bind (code out)
      (tf-frames "1.5" "--require" "l_gripper_tool_frame" "iai_kitchen/sink_area" "bottle_1"
                 "--chain" "map" "l_gripper_tool_frame")
    (is (eql 0 code) "tf_frames.py failed:~%~a" out)
    (is (search "dynamic map base_footprint" out))
    (is (search "dynamic l_gripper_palm_link l_gripper_tool_frame" out))
    (is (search "dynamic map bottle_1" out)))
  ;; the background thread follows the belief state; markers arrive on the marker topic
  (let ((tf (subscribe-collecting "/tf" "tf2_msgs/TFMessage"))
        (markers (subscribe-collecting "/visualization_marker_array" "visualization_msgs/MarkerArray")))
    (setf (btr:pose (btr:object btr:*current-bullet-world* :pr2)) '((1.25 0 0) (0 0 0 1)))
    (is-true (wait-until 5 (lambda () (let ((x (tf-x-of (funcall tf) "base_footprint")))
                                        (and x (< (abs (- x 1.25d0)) 1d-9))))))
    (is-true (wait-until 5 (lambda () (funcall markers))))
    (let* ((array (first (funcall markers)))
           (bottle (find-if (lambda (m) (search "bottle.stl" (visualization_msgs-msg:mesh_resource m)))
                            (visualization_msgs-msg:markers array))))
      (is-true bottle)
      (when bottle
        (is (string= "map" (std_msgs-msg:frame_id (visualization_msgs-msg:header bottle))))
        (is (string= "belief_state" (visualization_msgs-msg:ns bottle)))
        (is (< (abs (- 1.0 (std_msgs-msg:r (visualization_msgs-msg:color bottle)))) 1e-6))
        (is (< (abs (+ 2.0 (geometry_msgs-msg:x (geometry_msgs-msg:position (visualization_msgs-msg:pose bottle))))) 1e-6))))
    ;; a removed object's marker is deleted
    (btr:remove-object btr:*current-bullet-world* :bottle-1)
    (multiple-value-bind (transforms marker-count) (roslisp-utilities:publish-belief-state)
      (is (> transforms 150))
      (is (= 0 marker-count)))
    (is-true (wait-until 5 (lambda ()
                             (some (lambda (a)
                                     (some (lambda (m) (= 2 (visualization_msgs-msg:action m)))
                                           (visualization_msgs-msg:markers a)))
                                   (funcall markers))))))
  (is-true (roslisp-utilities:shutdown-ros))
  (is-false (roslisp-utilities:belief-state-publisher-running-p))
  (is (eq :shutdown (roslisp:node-status))))

(defun check-shop-world ()
  (let ((params (rosparam-list)))
    (is (member "/shelf_description" params :test #'string=)))
  (let ((roslisp-utilities:*ros-init-functions* '(init-shop-world)))
    (roslisp-utilities:startup-ros :publish-rate 20 :anonymous t))
  (is (equal '("/shelf_description" "/robot_description") *spawned-from*))
  (is (string= "pepper" (cl-urdf:name (btr:urdf (btr:object btr:*current-bullet-world* :pepper)))))
  (multiple-value-bind (code out)
      (tf-frames "1.5" "--require" "left_gripper_tip_frame" "dm_shelves/room_link"
                 "--chain" "map" "left_gripper_tip_frame")
    (is (eql 0 code) "tf_frames.py failed:~%~a" out)
    (is (search "dynamic map base_link" out)))
  (is-true (roslisp-utilities:shutdown-ros)))

(test live-ros-world-and-shop
  (let ((start (get-internal-real-time))
        (old-world btr:*current-bullet-world*)
        (old-robot rob-int:*robot-name*)
        (old-environment btr:*environment-name*)
        (left :not-run))
    ;; the publisher thread reads the global values
    (setf rob-int:*robot-name* nil btr:*environment-name* nil)
    (unwind-protect
         (setf left
               (call-with-private-ros
                (lambda ()
                  (is-true (roslisp-utilities:ros-available-p))
                  (let ((world (roslaunch "world" "launch/world.launch")))
                    (check-kitchen-world)
                    (stop-process world)
                    (setf (private-ros-processes *ros*) (remove world (private-ros-processes *ros*))))
                  (roslaunch "pepper" "launch/pepper.launch" "robot_tf:=false")
                  (check-shop-world))))
      (setf btr:*current-bullet-world* old-world
            rob-int:*robot-name* old-robot
            btr:*environment-name* old-environment))
    (is (null left) "processes left running after the test: ~s" left)
    (is (eq :shutdown (roslisp:node-status)))
    (is (< (seconds-since start) 60) "the live ROS test took ~,1f s" (seconds-since start))))
