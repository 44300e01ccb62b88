;;;; The same move-bottle plan over ROS against the simulated robot node at ten times the robot's
;;;; speed, against projection: wall time of the plan and the goals and trajectories the node got.

(defpackage :cram-bench.robot-ros
  (:use :cl :cram-bench))

(in-package :cram-bench.robot-ros)

(load-tool "demo.lisp" :cram-plans-demo)
(load-tool "robot-run.lisp")

(defun motion-count (counts)
  "Goals and trajectories the node received (perception messages left out)."
  (loop for (k . v) in counts unless (string= k "perception_requests") sum (or v 0)))

(define-benchmark move-bottle-over-ros ()
  (let* ((pose btw-tut:*bottle-pose-in-view*)
         (projection (median-seconds
                      (lambda ()
                        (cram-plans-demo:run-move-bottle pose :pictures nil
                                                              :log-stream (make-broadcast-stream)))
                      :runs 5))
         (motions (let ((n 0))
                    (cram-plans-demo:run-move-bottle pose :pictures nil :log-stream (make-broadcast-stream))
                    (cpl:find-task-tree-nodes (lambda (node) (and (eq (cpl:node-kind node) :motion) (incf n))))
                    n))
         (ros (let ((*standard-output* (make-broadcast-stream)) (cpl:*log-stream* (make-broadcast-stream)))
                (cram-plans-demo::run-move-bottle-over-ros :speed 10 :pose pose))))
    (if (getf ros :success)
        (add-row (format nil "move-bottle over ROS at 10x robot speed (~d goals and trajectories; ~
                              ~d motions in projection)"
                         (motion-count (getf ros :counts)) motions)
                 (format-seconds (getf ros :seconds))
                 :peer-name "the same plan in projection" :peer (format-seconds projection)
                 :ratio (/ (getf ros :seconds) projection))
        (add-row "move-bottle over ROS at 10x robot speed" "failed"
                 :goal (format nil "succeeds (~a)" (or (getf ros :error) (getf ros :distance)))
                 :met nil))))
