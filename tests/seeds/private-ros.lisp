;;;; A private ROS master for seed replays: the pages start with `roslaunch ...', which the
;;;; replay does on a free port with ROS_HOME under /tmp, so replays never meet another master.

(in-package :cram-plans-seeds)

(export '(start-private-ros stop-private-ros ros-run free-port))

(defvar *ros-dir* nil "ROS_HOME of the private master, removed when it stops.")
(defvar *ros-processes* '() "The processes of the private master and its launch file.")

(defun free-port ()
  "A TCP port of 127.0.0.1 that nothing listens on now."
  (let ((s (make-instance 'sb-bsd-sockets:inet-socket :type :stream :protocol :tcp)))
    (unwind-protect
         (progn (sb-bsd-sockets:socket-bind s #(127 0 0 1) 0)
                (nth-value 1 (sb-bsd-sockets:socket-name s)))
      (sb-bsd-sockets:socket-close s))))

(defun ros-run (program &rest args)
  "Run PROGRAM with ARGS against the private master; its output as a string."
  (uiop:run-program (cons program args) :output :string :ignore-error-status t
                                        :error-output :output))

(defun stop-private-ros ()
  "Stop the private master and its launch file (SIGINT, then SIGKILL) and remove its ROS_HOME."
  (dolist (p *ros-processes*)
    (when (sb-ext:process-alive-p p)
      (ignore-errors (sb-posix:kill (- (sb-ext:process-pid p)) sb-posix:sigint))))
  (loop repeat 50 while (some #'sb-ext:process-alive-p *ros-processes*) do (sleep 0.1))
  (dolist (p *ros-processes*)
    (when (sb-ext:process-alive-p p)
      (ignore-errors (sb-posix:kill (- (sb-ext:process-pid p)) sb-posix:sigkill))))
  (setf *ros-processes* '())
  (when *ros-dir*
    (uiop:delete-directory-tree (uiop:ensure-directory-pathname *ros-dir*) :validate t
                                                                           :if-does-not-exist :ignore)
    (setf *ros-dir* nil)))

(defun start-private-ros (launch-file)
  "`roslaunch LAUNCH-FILE' (a path relative to the checkout, e.g. \"launch/world.launch\") with
its own master on a free port, ROS_HOME under /tmp; returns when the map server is up."
  (let* ((port (free-port))
         (dir (format nil "/tmp/cram-seed-~a-ros-~d/" (seed-number *seed*) (sb-posix:getpid)))
         (log (format nil "~aroslaunch.log" dir)))
    (setf *ros-dir* dir)
    (ensure-directories-exist (format nil "~alog/" dir))
    (sb-posix:setenv "ROS_MASTER_URI" (format nil "http://127.0.0.1:~d" port) 1)
    (sb-posix:setenv "ROS_HOME" dir 1)
    (sb-posix:setenv "ROS_LOG_DIR" (format nil "~alog" dir) 1)
    (sb-posix:setenv "ROS_IP" "127.0.0.1" 1)
    (sb-posix:unsetenv "ROS_HOSTNAME")
    (pushnew 'stop-private-ros sb-ext:*exit-hooks*)
    (let ((p (sb-ext:run-program "roslaunch"
                                 (list "-p" (princ-to-string port)
                                       (namestring (merge-pathnames launch-file *checkout*)))
                                 :search t :wait nil :input nil :output log
                                 :if-output-exists :supersede :error :output
                                 :environment (sb-ext:posix-environ))))
      (ignore-errors (sb-posix:setpgid (sb-ext:process-pid p) (sb-ext:process-pid p)))
      (push p *ros-processes*))
    (expect (loop repeat 200 thereis (search "/map_server" (ros-run "rosnode" "list"))
                  do (sleep 0.2))
            "roslaunch ~a did not bring up /map_server; log:~%~a" launch-file
            (ignore-errors (uiop:read-file-string log)))))
