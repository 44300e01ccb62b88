;;;; Tests of what a plan writes when nobody reads it: log lines to a stream that discards
;;;; everything are not formatted, CPL:*LOG-TALLY* still counts them by tag, and a task tree
;;;; node given its designator as a function prints it only when asked.

(in-package :cram-language-tests)

(in-suite language)

(defclass counted-printing ()
  ((prints :initform 0 :accessor prints))
  (:documentation "An object that counts how often it is printed."))

(defmethod print-object ((object counted-printing) stream)
  (incf (prints object))
  (format stream "#<COUNTED-PRINTING ~d>" (prints object)))

(deftest log-to-a-sink-is-not-formatted-but-tallied
  (let* ((object (make-instance 'counted-printing))
         (tally (make-hash-table :test 'equal))
         (cpl:*log-tally* tally))
    ;; a broadcast stream without components discards everything: nothing is formatted
    (let ((cpl:*log-stream* (make-broadcast-stream)))
      (is (null (cpl:log-message :info '(pick-place pick-up) "Reaching ~a" object)))
      (is (null (cpl:log-message :warn 'grasp-failure "Failed: ~a" object)))
      (cpl:log-debug "below the level: neither written nor counted ~a" object))
    (is (= 0 (prints object)))
    ;; a stream someone reads gets the line, and the tally counts it too
    (let* ((out (make-string-output-stream))
           (cpl:*log-stream* out))
      (is (equal "Reaching #<COUNTED-PRINTING 1>"
                 (cpl:log-message :info '(pick-place pick-up) "Reaching ~a" object)))
      (is (search "[(PICK-PLACE PICK-UP) INFO]" (get-output-stream-string out))))
    (is (= 2 (gethash '(:info pick-place pick-up) tally)))
    (is (= 1 (gethash '(:warn grasp-failure) tally)))
    (is (= 2 (hash-table-count tally)))
    ;; bad input is still an error on a sink
    (let ((cpl:*log-stream* (make-broadcast-stream)))
      (signals error (cpl:log-message :loud nil "x"))
      (signals error (cpl:log-message :info nil 42))))
  ;; without a tally nothing is counted, and a stream that echoes somewhere is not a sink
  (let* ((out (make-string-output-stream))
         (cpl:*log-stream* (make-broadcast-stream out)))
    (is (equal "shown" (cpl:log-info "shown")))
    (is (search "shown" (get-output-stream-string out)))))

(deftest log-tally-counts-in-child-tasks
  (let ((tally (make-hash-table :test 'equal))
        (cpl:*log-stream* (make-broadcast-stream)))
    (let ((cpl:*log-tally* tally))
      (top-level
        (par (cpl:log-message :info '(trying-new-grasp) "Trying to grasp from ~a" :front)
             (cpl:log-message :info '(trying-new-grasp) "Trying to grasp from ~a" :back)
             (cpl:with-log-tags (:demo) (cpl:log-warn "careful")))))
    (is (= 2 (gethash '(:info trying-new-grasp) tally)))
    (is (= 1 (gethash '(:warn :demo) tally)))))

(deftest task-tree-node-prints-its-designator-when-asked
  (let* ((object (make-instance 'counted-printing))
         (root (cpl::make-task-tree-node :top-level 'root))
         (node (cpl::make-task-tree-node :action 'reaching :designator (lambda () object)
                                                           :parent root)))
    (is (= 0 (prints object)) "making the node prints nothing")
    (let ((text (cpl:node-designator node)))
      (is (equal "#<COUNTED-PRINTING 1>" text))
      (is (eq text (cpl:node-designator node)) "printed once, then kept"))
    (is (= 1 (prints object)))
    ;; any other object is printed at once: it might change before anyone asks
    (let* ((state (list 0))
           (node (cpl::make-task-tree-node :motion 'reach :designator (list :reach state))))
      (setf (car state) 3)
      (is (equal "(:REACH (0))" (cpl:node-designator node))))
    (is (equal "(A MOTION)" (cpl:node-designator
                             (cpl::make-task-tree-node :motion 'm :designator "(A MOTION)"))))
    (is (null (cpl:node-designator (cpl::make-task-tree-node :plan 'p))))))
