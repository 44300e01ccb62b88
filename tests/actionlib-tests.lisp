;;;; CRAM's actionlib client API (packages ACTIONLIB and ACTIONLIB-CLIENT) and the example
;;;; process module of a user's own gripper (examples/my-gripper.lisp), against a rospy action
;;;; server (tools/ros/gripper_action_server.py) on a private ROS master.

(defpackage :cram-plans-tests-actionlib
  (:use :cl :fiveam))

(in-package :cram-plans-tests-actionlib)

(def-suite actionlib :in cram-plans-tests:all
  :description "CRAM's actionlib client and a user's gripper process module over ROS.")

(in-suite actionlib)

(defun checkout-file (name)
  (namestring (merge-pathnames name (asdf:system-source-directory "cram-plans/tests/base"))))

(defun setup-failure (e)
  "An error for a failed setup: the backtrace first and the cause last, so that the cause is in
what a log's tail shows."
  (error "Setting up the gripper's server failed.~%~{  ~s~%~}Cause: ~a"
         (sb-debug:list-backtrace :count 12) e))

(defun start-gripper-server ()
  "A private master, the gripper's action server and a node of this process (a node left running
by an earlier test is stopped first: it talks to another master)."
  (roslisp-utilities:shutdown-ros)
  (cram-ros-pms::start-private-ros)
  (cram-ros-pms::start-group cram-ros-pms::*private-ros* "my_gripper" "/usr/bin/python3"
                             (checkout-file "tools/ros/gripper_action_server.py"))
  (roslisp:start-ros-node "actionlib_test" :anonymous t))

(defun stop-gripper-server ()
  (actionlib-client:destroy-simple-action-clients)
  (ignore-errors (roslisp-utilities:shutdown-ros))
  (cram-ros-pms::stop-private-ros))

(defun call-with-gripper-server (thunk)
  "THUNK with the gripper's server up. The setup depends on the machine (free ports, a loaded
CPU): a failed first try is reported on *ERROR-OUTPUT* and made once more from scratch."
  (unwind-protect
       (progn
         (handler-case (start-gripper-server)
           (error (e)
             (format *error-output* "~&;; gripper server setup failed, trying once more: ~a~%" e)
             (ignore-errors (stop-gripper-server))
             (sleep 1)
             (handler-bind ((error #'setup-failure))
               (start-gripper-server))))
         (funcall thunk))
    (stop-gripper-server)))

(defun goal (client mm)
  (actionlib:make-action-goal client goal mm))

(test actionlib-client-and-a-users-gripper-process-module
  (call-with-gripper-server
   (lambda ()
     (let ((client (actionlib:make-action-client "/my_gripper/command" "actionlib/TestAction")))
       (is (actionlib:wait-for-server client 30) "the gripper's action server did not come up")
       (is (actionlib:connected-to-server client))
       ;; SEND-GOAL with feedback and done callbacks, WAIT-FOR-RESULT, the goal's state
       (let* ((feedback '()) (done nil)
              (handle (actionlib:send-goal client (goal client 40)
                                           :feedback-cb (lambda (f) (push (actionlib-msg:feedback f) feedback))
                                           :done-cb (lambda (state result)
                                                      (setf done (list state (actionlib-msg:result result)))))))
         (is (member (actionlib:goal-state handle) '(:pending :active)))
         (is (actionlib:wait-for-result handle 20))
         (is (eq :succeeded (actionlib:goal-state handle)))
         (is (actionlib:terminal-state-p (actionlib:goal-state handle)))
         (is (= 40 (actionlib-msg:result (actionlib:result handle))))
         ;; 10, 20, 30 and 40 mm in order (the last may come after the result)
         (is (member (reverse feedback) '((10 20 30 40) (10 20 30)) :test #'equal) "feedback ~s" feedback)
         (is (equal '(:succeeded 40) done))
         (is (search "reached" (actionlib:goal-status-text handle))))
       ;; CALL-GOAL: a refused goal is aborted, a slow one cancelled after the timeout
       (multiple-value-bind (result state) (actionlib:call-goal client (goal client 200) :timeout 20)
         (is (eq :aborted state))
         (is (= 40 (actionlib-msg:result result))))
       (multiple-value-bind (result state handle) (actionlib:call-goal client (goal client 0) :timeout 0.15)
         (is (null result))
         (is (eq :timeout state))
         (is (actionlib:wait-for-result handle 20))
         (is (eq :preempted (actionlib:goal-state handle))))
       (let ((handle (actionlib:send-goal client (goal client 90))))
         (sleep 0.15)
         (actionlib:cancel-goal handle)
         (is (actionlib:wait-for-result handle 20))
         (is (eq :preempted (actionlib:goal-state handle)))
         (is (< 0 (actionlib-msg:result (actionlib:result handle)) 90)))
       ;; bad input names the value
       (signals error (actionlib:make-action-client "/my_gripper/command" "no_such_msgs/Nothing"))
       (signals error (actionlib:make-action-client "/my_gripper/command" 'gripper))
       (signals error (actionlib:send-goal client "open"))
       (signals error (actionlib:wait-for-result :handle))
       (signals error (actionlib:wait-for-server client -1)))
     ;; no server: SERVER-LOST
     (let ((actionlib:*action-server-timeout* 0.3))
       (let ((nobody (actionlib:make-action-client "/nobody/command" "actionlib/TestAction")))
         (is (not (actionlib:wait-for-server nobody 0.2)))
         (signals actionlib:server-lost (actionlib:call-goal nobody (goal nobody 1)))))
     ;; the example process module, as the README shows it
     (load (checkout-file "examples/my-gripper.lisp"))
     (funcall (find-symbol "INIT-MY-GRIPPER" :my-gripper))
     (let ((pm (find-symbol "MY-GRIPPER-PM" :my-gripper))
           (goals-before (roslisp:get-param "/my_gripper/goals")))
       (flet ((perform-opening (opening)
                (cpl:top-level
                  (cpm::call-with-process-modules-running
                   (list pm)
                   (lambda ()
                     (exe:perform (desig:make-designator
                                   :motion `((:type :setting-my-gripper) (:opening ,opening)))))))))
         (is (= 0.06d0 (perform-opening 0.06)))
         (is (= 0.03d0 (perform-opening 0.03)))
         (is (eql 30 (roslisp:get-param "/my_gripper/opening")))
         ;; from 60 mm down to 30 mm: feedback on the way (the last may come after the result)
         (let ((feedback (symbol-value (find-symbol "*GRIPPER-FEEDBACK*" :my-gripper))))
           (is (consp feedback))
           (is (every (lambda (opening) (<= 0.03d0 opening 0.05d0)) feedback) "feedback ~s" feedback))
         (signals common-fail:gripper-goal-not-reached (perform-opening 0.5))
         (is (eql 3 (- (roslisp:get-param "/my_gripper/goals") goals-before))
             "the example's process module did not send its three goals"))))))

(defun documented-p (symbol)
  (some (lambda (kind) (ignore-errors (documentation symbol kind)))
        '(function variable type structure)))

(test actionlib-packages-are-documented
  (dolist (package '(:actionlib :actionlib-client))
    (is (documentation (find-package package) t))
    (do-external-symbols (symbol package)
      (is (documented-p symbol) "~s has no docstring" symbol)))
  (dolist (symbol '(cpl:*debug-on-lisp-errors* cpl:*break-on-plan-failures* cpl:abort-plan
                    cpl:plan-aborted cpl:plan-aborted-name
                    cpm:*process-module-debugger-hook* cpm:continue-pm))
    (is (documented-p symbol) "~s has no docstring" symbol)))
