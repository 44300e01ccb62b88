;;;; Tests of fluents, the task tree, logging and the common failures.

(in-package :cram-language-tests)

(in-suite language)

;;; Fluents

(deftest wait-for-value-from-another-thread
  (let* ((fluent (make-fluent :name 'door :value nil))
         (setter (bt:make-thread (lambda () (cl:sleep 0.05) (setf (value fluent) 42))))
         (start (get-internal-real-time)))
    (is (eql 42 (wait-for fluent :timeout 5)))
    (is (< (elapsed-since start) 4))
    (bt:join-thread setter))
  (let ((fluent (make-fluent)))
    (is (eql :open (top-level
                     (par (wait-for fluent)
                          (progn (cpl:sleep 0.03) (setf (value fluent) :open))))))))

(deftest wait-for-timeout
  (let ((fluent (make-fluent :value nil))
        (start (get-internal-real-time)))
    (is (null (wait-for fluent :timeout 0.1)))
    (is (>= (elapsed-since start) 0.09)))
  (is (eq :ready (wait-for (make-fluent :value :ready) :timeout 0)))
  (signals error (wait-for (make-fluent) :timeout -1))
  (signals error (setf (value 3) 4)))

(deftest fluent-networks
  (let* ((x (make-fluent :value 1))
         (y (make-fluent :value 5))
         (less (fl< x y))
         (both (fl-and less (fl-not (make-fluent :value nil))))
         (sum (fl-funcall #'+ x y 10)))
    (is (eq t (value less)))
    (is (eq t (value both)))
    (is (= 16 (value sum)))
    (setf (value x) 7)
    (is (null (value less)))
    (is (null (value both)))
    (is (eq :yes (value (fl-or (fl= x 3) :yes))))
    ;; waiting on a network wakes up when a dependency changes
    (let ((setter (bt:make-thread (lambda () (cl:sleep 0.05) (setf (value y) 100)))))
      (is (eq t (wait-for (fl> y x) :timeout 5)))
      (bt:join-thread setter))))

(deftest whenever-and-pulsed
  (let ((fluent (make-fluent :value nil)) (seen '()))
    (top-level
      (par (whenever (fluent)
             (push (value fluent) seen)
             (when (eql (value fluent) 3) (return)))
           (loop for v in '(1 2 3)
                 do (cpl:sleep 0.03) (setf (value fluent) v))))
    (is (equal '(3 2 1) seen)))
  (let* ((fluent (make-fluent :value 0))
         (pulse (pulsed fluent)))
    (is (null (value pulse)))
    (setf (value fluent) 1)
    (setf (value fluent) 2)
    (is (eq t (value pulse)))
    (is (null (value pulse)) "a pulse is consumed by reading it")))

(deftest sleep-uses-replaceable-clock
  (let ((slept '()) (lock (sb-thread:make-mutex :name "slept")))
    ;; the two branches sleep in two threads: record under a lock, no push may be lost
    (let ((cpl:*sleep-function* (lambda (s) (sb-thread:with-mutex (lock) (push s slept)))))
      (top-level (par (cpl:sleep 30) (cpl:sleep 2.5))))
    (is (equal '(30 2.5) (sort slept #'>)))
    (signals error (cpl:sleep -1))
    (signals error (cpl:sleep :soon))))

;;; Task tree

(cpl:def-cram-function tree-test-grasp (object)
  "Fail twice, then succeed."
  (cpl:with-task-tree-node (:motion 'reach :designator (list :reach object))
    (with-retry-counters ((tries 3))
      (with-failure-handling ((common-fail:manipulation-pose-unreachable ()
                                (do-retry tries (retry))))
        (when (< (incf (car object)) 3)
          (fail 'common-fail:manipulation-pose-unreachable
                :description "no IK solution"))
        :grasped))))

(cpl:def-cram-function tree-test-plan ()
  (let ((counter (list 0)))
    (par (tree-test-grasp counter)
         (handler-case (cpl:with-task-tree-node (:action 'doomed)
                         (fail 'common-fail:object-unreachable :description "too far"))
           (plan-failure () :gave-up)))))

(defun node-named (name)
  (first (cpl:find-task-tree-nodes (lambda (n) (equal (cpl:node-name n) name)))))

(deftest task-tree-records-nodes-failures-retries
  (is (eq :gave-up (named-top-level (:name 'tree-test) (tree-test-plan))))
  (let* ((root cpl:*last-task-tree*)
         (plan (node-named 'tree-test-plan))
         (reach (node-named 'reach))
         (doomed (node-named 'doomed)))
    (is (eq :top-level (cpl:node-kind root)))
    (is (eq :succeeded (cpl:node-outcome root)))
    (is (eq :plan (cpl:node-kind plan)))
    (is (eq :motion (cpl:node-kind reach)))
    (is (= 2 (cpl:node-retries reach)))
    (is (equal '(common-fail:manipulation-pose-unreachable
                 common-fail:manipulation-pose-unreachable)
               (mapcar (lambda (f) (getf f :class)) (cpl:node-caught-failures reach))))
    (is (search "no IK solution" (getf (first (cpl:node-caught-failures reach)) :description)))
    (is (search "(:REACH (0))" (cpl:node-designator reach)))
    (is (eq :failed (cpl:node-outcome doomed)))
    (is (eq 'common-fail:object-unreachable (getf (cpl:node-failure doomed) :class)))
    (is (= 2 (count :par-child (cpl:find-task-tree-nodes (constantly t)) :key #'cpl:node-kind)))
    (is (every (lambda (n) (and (cpl:node-end-unix n)
                                (>= (cpl:node-end-unix n) (cpl:node-start-unix n))))
               (cpl:find-task-tree-nodes (constantly t))))))

(deftest task-tree-json-round-trip
  (named-top-level (:name 'tree-test) (tree-test-plan))
  (let* ((json (yason:parse (cpl:task-tree-to-json)))
         (nodes '()))
    (labels ((walk (node) (push node nodes) (map nil #'walk (gethash "children" node))))
      (walk json))
    (is (string= "top-level" (gethash "kind" json)))
    (is (string= "succeeded" (gethash "outcome" json)))
    (let ((reach (find "reach" nodes :key (lambda (n) (gethash "name" n)) :test #'string=))
          (doomed (find "doomed" nodes :key (lambda (n) (gethash "name" n)) :test #'string=)))
      (is (= 2 (gethash "retries" reach)))
      (is (= 2 (length (gethash "caught_failures" reach))))
      (is (string= "failed" (gethash "outcome" doomed)))
      (is (string= "OBJECT-UNREACHABLE" (gethash "class" (gethash "failure" doomed))))
      (is (realp (gethash "duration_s" reach)))))
  (signals error (cpl:task-tree-to-json :not-a-node)))

(deftest task-tree-evaporated-and-html
  (is (typep (handler-case
                 (named-top-level (:name 'evaporation)
                   (par (cpl:with-task-tree-node (:action 'endless) (loop (cpl:sleep 0.01)))
                        (progn (cpl:sleep 0.03) (fail 'failure-a))))
               (plan-failure (c) c))
             'failure-a))
  (is (eq :evaporated (cpl:node-outcome (node-named 'endless))))
  (is (eq :failed (cpl:node-outcome cpl:*last-task-tree*)))
  (let ((path (format nil "/tmp/cram-language-test-~d.html" (get-universal-time))))
    (unwind-protect
         (progn
           (cpl:write-task-tree-html path)
           (let ((text (alexandria:read-file-into-string path)))
             (is (search "<!DOCTYPE html>" text))
             (is (search "endless" text))
             (is (search "evaporated" text))
             (is (search "FAILURE-A" text))))
      (when (probe-file path) (delete-file path)))))

(deftest task-tree-html-links-pictures-and-folds-designators
  (let* ((dir (format nil "/tmp/cram-language-pics-~d/" (get-universal-time)))
         (path (concatenate 'string dir "tree.html")))
    (named-top-level (:name 'pictured)
      (cpl:with-task-tree-node (:motion 'moving :designator "(A MOTION (TYPE GOING))")
        (cpl:note-picture (concatenate 'string dir "001-going.png"))))
    (is (equal (list (concatenate 'string dir "001-going.png"))
               (cpl:node-pictures (node-named 'moving))))
    (is (equal "ignored.png" (cpl:note-picture "ignored.png" nil)) "outside a plan: nothing noted")
    (unwind-protect
         (progn
           (cpl:write-task-tree-html path)
           (let ((text (alexandria:read-file-into-string path)))
             (is (search "href=\"001-going.png\"" text) "the picture is linked relative to the page")
             (is (search "<details class=\"desig\"><summary>designator</summary>" text)
                 "the designator is folded away")
             (is (not (search "<details class=\"desig\" open" text)))
             (is (search " UTC" text) "times are human times")
             (is (search "(A MOTION (TYPE GOING))" text))))
      (uiop:delete-directory-tree (uiop:ensure-directory-pathname dir) :validate t
                                                                       :if-does-not-exist :ignore))))

;;; Logging

(deftest log-line-shape
  (let* ((out (make-string-output-stream))
         (cpl:*log-stream* out))
    (cpl:log-message :info '(pick-place pick-up) "Opening gripper ~a" :left)
    (cpl:with-log-tags (:demo)
      (cpl:log-warn "careful"))
    (cpl:log-debug "hidden by the default level")
    (let ((lines (with-input-from-string (s (get-output-stream-string out))
                   (loop for l = (read-line s nil) while l collect l))))
      (is (= 2 (length lines)))
      (is (eql 0 (search "[(PICK-PLACE PICK-UP) INFO] " (first lines))))
      (is (search ": Opening gripper LEFT" (first lines)))
      (let ((stamp (subseq (first lines) 27 (search ": " (first lines)))))
        (is (= 3 (- (length stamp) (1+ (position #\. stamp)))))
        (is (< (abs (- (let ((*read-default-float-format* (quote double-float)))
                                 (read-from-string stamp))
                               (cpl:unix-time)))
               5)))
      (is (eql 0 (search "[(DEMO) WARN] " (second lines))))))
  (signals error (cpl:log-message :loud nil "x")))

;;; Common failures

(deftest common-failure-hierarchy-and-reports
  (is (subtypep 'common-fail:torso-goal-not-reached 'common-fail:manipulation-low-level-failure))
  (is (subtypep 'common-fail:perception-object-not-found 'common-fail:low-level-failure))
  (is (subtypep 'common-fail:delivering-failed 'common-fail:high-level-failure))
  (is (subtypep 'common-fail:high-level-failure 'simple-plan-failure))
  (let ((c (make-condition 'common-fail:perception-object-not-found
                           :description "nothing on the table" :object '(:bottle))))
    (is (equal '(:bottle) (common-fail:perception-failure-object c)))
    (is (search "PERCEPTION-OBJECT-NOT-FOUND: nothing on the table" (princ-to-string c))))
  (is (search "LOOKING-HIGH-LEVEL-FAILURE"
              (princ-to-string (make-condition 'common-fail:looking-high-level-failure)))))

(deftest retry-with-list-solutions-walks-lazy-list
  (let ((tried '())
        (cpl:*log-stream* (make-broadcast-stream)))
    (is (eq :c (top-level
                 (let ((candidates (cut:lazy-mapcar #'identity '(:a :b :c :d))))
                   (with-retry-counters ((tries 5))
                     (with-failure-handling
                         ((failure-a (e)
                            (common-fail:retry-with-list-solutions candidates tries
                                (:error-object-or-string e :warning-namespace (test))
                              (push :next tried))))
                       (let ((candidate (cut:lazy-car candidates)))
                         (push candidate tried)
                         (if (eq candidate :c) :c (fail 'failure-a)))))))))
    (is (equal '(:c :next :b :next :a) tried))))

(defclass counting-designator ()
  ((n :initarg :n :reader designator-n)))

(defmethod common-fail:designator-next-solution ((d counting-designator))
  (when (< (designator-n d) 3)
    (make-instance 'counting-designator :n (1+ (designator-n d)))))

(deftest retry-with-designator-solutions-and-rethrow
  (let ((cpl:*log-stream* (make-broadcast-stream))
        (seen '()))
    (let ((c (handler-case
                 (top-level
                   (let ((desig (make-instance 'counting-designator :n 0)))
                     (with-retry-counters ((tries 10))
                       (with-failure-handling
                           ((failure-b (e)
                              (common-fail:retry-with-designator-solutions desig tries
                                  (:error-object-or-string e
                                   :rethrow-failure 'common-fail:object-unfetchable))))
                         (push (designator-n desig) seen)
                         (fail 'failure-b)))))
               (plan-failure (c) c))))
      (is (equal '(3 2 1 0) seen))
      (is (typep c 'common-fail:object-unfetchable))))
  (signals error (common-fail:designator-next-solution :not-a-designator)))

(defmethod common-fail:designator-next-different-location-solution
    ((d counting-designator) distance-threshold angle-threshold)
  (declare (ignore angle-threshold))
  ;; jumps by the distance threshold, as a stand-in for "far enough away"
  (let ((next (+ (designator-n d) (round distance-threshold))))
    (when (< next 10)
      (make-instance 'counting-designator :n next))))

(deftest retry-with-loc-designator-solutions-uses-threshold
  (let ((cpl:*log-stream* (make-broadcast-stream))
        (seen '()))
    (is (eq :found
            (top-level
              (let ((location (make-instance 'counting-designator :n 0)))
                (with-retry-counters ((tries 2))
                  (with-failure-handling
                      ((failure-c (e)
                         (common-fail:retry-with-loc-designator-solutions location tries
                             (:error-object-or-string e :distance-threshold 4))))
                    (push (designator-n location) seen)
                    (if (= (designator-n location) 8) :found (fail 'failure-c))))))))
    (is (equal '(8 4 0) seen))))

;;; Goals

(cpl:declare-goal achieve-test-goal (occasion)
  "A goal for the tests.")

(cpl:def-goal (achieve-test-goal (object-in-hand ?object ?object))
  (list :same ?object))

(cpl:def-goal (achieve-test-goal (object-in-hand ?object ?hand))
  (list :holding ?object ?hand))

(cpl:def-goal (achieve-test-goal (robot-at ?location))
  (list :at ?location))

(deftest goals-dispatch-on-patterns
  (is (equal '(:holding :cup :left) (achieve-test-goal '(object-in-hand :cup :left))))
  (is (equal '(:same :cup) (achieve-test-goal '(object-in-hand :cup :cup))))
  (is (equal '(:at (1 2)) (achieve-test-goal '(robot-at (1 2)))))
  (signals error (achieve-test-goal '(flying)))
  (top-level (achieve-test-goal '(robot-at :table)))
  (is (eq :goal (cpl:node-kind (first (cpl:node-children cpl:*last-task-tree*))))))
