;;;; Benchmark of cram-native against the raw C++ program tests/bench/native/raw_bench.cpp
;;;; (the same operations written directly on Bullet), measured in the same run.  Both sides
;;;; report the fastest of their batches.  The shim brings broadphase bounding boxes of moved
;;;; bodies up to date at the next query, the raw program at every move: the rows "..., then
;;;; its contacts" and "..., then robot collision check" time the whole cycle on both sides.

(require :asdf)
(require :sb-posix)
(asdf:load-system "cram-plans/cram-native")
(asdf:load-system "cram-plans/tests/base")

(defpackage :cram-native-bench (:use :cl :cram-native))
(in-package :cram-native-bench)

(defparameter *native-dir* (asdf:system-relative-pathname "cram-plans/cram-native" "projection/native/"))
(defparameter *shared-models* (cram-plans-tests:shared-models-directory)
  "../shared/models/ beside the checkout: reference models tests may read, never commit.")
(defparameter *pr2-urdf* (merge-pathnames "pr2_description/urdf/pr2.urdf" *shared-models*))

(defun chain-urdf (n)
  "URDF of a chain of N revolute joints (axes alternating z and y) with box links, the robot
of raw_bench.cpp."
  (with-output-to-string (s)
    (format s "<robot name='chain'><link name='l0'/>")
    (loop for j from 1 to n
          do (format s "<link name='l~d'><collision><geometry><box size='0.04 0.04 0.08'/></geometry></collision></link>
<joint name='j~d' type='revolute'><parent link='l~d'/><child link='l~d'/><origin xyz='0 0 ~a'/><axis xyz='~a'/><limit lower='-3' upper='3' effort='1' velocity='1'/></joint>"
                     j j (1- j) j (if (= j 1) "0.05" "0.08") (if (oddp j) "0 0 1" "0 1 0")))
    (format s "</robot>")))

(defun build-scene ()
  "Plane, 33 boxes and the 45-joint chain robot (as in raw_bench.cpp)."
  (let ((w (make-world)) (boxes '()))
    (add-plane w)
    (dotimes (i 33)
      (push (add-box w (list (+ 1 (* 0.3 (mod i 6))) (- (* 0.3 (floor i 6)) 0.8)
                             (+ 0.05 (* 0.12 (mod i 3))) 0 0 0 1)
                     '(0.1 0.1 0.1) :mass 1)
            boxes))
    (values w (add-urdf w (chain-urdf 45)) (reverse boxes))))

(defparameter *processes* 3
  "Processes each side of the per-call teleport row is measured in: its time depends on where a
process's heap, stacks and libraries lie (aliasing of loads and stores), so both sides report
the median over several processes, run in interleaved rounds (one of ours, one of the raw
program's) so that a noisy stretch of the machine's load falls on both sides.")

(defun parse-times (out)
  "Alist (name . seconds) of the lines \"name seconds\" of OUT."
  (with-input-from-string (s out)
    (loop for line = (read-line s nil) while line
          for sp = (position #\Space line)
          for value = (and sp (ignore-errors
                               (let ((*read-default-float-format* 'double-float)
                                     (*read-eval* nil))
                                 (read-from-string (subseq line (1+ sp))))))
          when (realp value)
            collect (cons (subseq line 0 sp) (coerce value 'double-float)))))

(defun median (xs)
  (let ((v (sort (copy-list xs) #'<)) (n (length xs)))
    (if (oddp n) (nth (floor n 2) v) (* 0.5d0 (+ (nth (1- (floor n 2)) v) (nth (floor n 2) v))))))

(defun raw-times ()
  "Alist (name . seconds) from the raw C++ program, each the median over *PROCESSES* runs, or
NIL when it cannot be built or run."
  (ignore-errors
   (uiop:run-program (list "make" "-s" "-C" (namestring *native-dir*) "bench")
                     :output nil :error-output nil)
   (let ((runs (loop repeat *processes*
                     for out = (cram-bench:run-peer (namestring (merge-pathnames "build/raw_bench" *native-dir*)))
                     when out collect (parse-times out))))
     (when runs
       (loop for (name . nil) in (first runs)
             collect (cons name (median (loop for r in runs
                                              for v = (cdr (assoc name r :test #'string=))
                                              when v collect v))))))))

(defun row (measure ours raw-name raw &key (goal-ratio 1.2d0) goal-abs)
  (let* ((peer (cdr (assoc raw-name raw :test #'string=)))
         (ratio (and peer (/ ours peer))))
    (cram-bench:add-row measure (cram-bench:format-seconds ours)
                        :peer-name (and peer "raw C++ Bullet") :peer (and peer (cram-bench:format-seconds peer))
                        :ratio ratio
                        :goal (cond (goal-abs (format nil "<= ~a" (cram-bench:format-seconds goal-abs)))
                                    (goal-ratio (format nil "<= ~,1fx raw" goal-ratio)))
                        :met (cond (goal-abs (<= ours goal-abs))
                                   ((null goal-ratio) :unknown)
                                   (ratio (<= ratio goal-ratio))
                                   (t :unknown)))
    ours))

(defun anchor (measure ours pybullet)
  "Add a row comparing OURS (seconds) with the PyBullet 3.2.7 figure PYBULLET of
../shared/docs/anchors.md for the same operation (PyBullet is not installable here)."
  (cram-bench:add-row (format nil "~a, vs PyBullet" measure) (cram-bench:format-seconds ours)
                      :peer-name "PyBullet 3.2.7 (anchors.md)"
                      :peer (format nil "~~~a" (cram-bench:format-seconds pybullet))
                      :ratio (/ ours pybullet) :goal nil :met :unknown))

;;; IK on random reachable poses of the PR2 arms

(defparameter *ik-urdf*
  (let ((own (asdf:system-relative-pathname "cram-plans/cram-native" "robots/pr2/pr2.urdf")))
    (if (probe-file own) own *pr2-urdf*))
  "The PR2 model of the IK benchmark.")

(defparameter *ik-poses* 1000 "Random reachable poses per arm.")
(defparameter *ik-peer-poses* 300 "Poses per arm solved by the KDL peer.")

(defun ik-peer-times ()
  "Alist (\"kdl-mean:TIP\" . seconds) etc. from tests/bench/native/ik_bench.cpp: KDL's LMA
solver with random restarts on the same kind of poses, or NIL when it cannot run."
  (ignore-errors
   (let ((out (cram-bench:run-peer (namestring (merge-pathnames "build/ik_bench" *native-dir*))
                                   (namestring *ik-urdf*) "--machine" "--poses" "1"
                                   "--peer" (princ-to-string *ik-peer-poses*)
                                   "--search-dir" *shared-models*
                                   "--tip" "l_wrist_roll_link" "--tip" "r_wrist_roll_link")))
     (when out
       (with-input-from-string (s out)
         (loop for line = (read-line s nil) while line
               collect (let ((sp (position #\Space line)))
                         (cons (subseq line 0 sp)
                               (let ((*read-default-float-format* 'double-float))
                                 (coerce (read-from-string (subseq line (1+ sp))) 'double-float))))))))))

(defun wall-seconds ()
  "Wall-clock time in seconds, to the microsecond."
  (multiple-value-bind (sec usec) (sb-ext:get-time-of-day)
    (+ sec (* 1d-6 usec))))

(defun ik-arm-row (w r side tip peers)
  "Solve *IK-POSES* random reachable poses of the chain torso_lift_link -> TIP from random
seeds within the limits; add a row with the mean time, the solved share and the worst errors."
  (let* ((c (make-chain w r "torso_lift_link" tip))
         (state (sb-ext:seed-random-state 7))
         (n *ik-poses*) (solved 0) (worst-pos 0d0) (worst-rot 0d0))
    (unwind-protect
         (multiple-value-bind (lo hi) (chain-limits c)
           (flet ((draw () (map '(simple-array double-float (*))
                                (lambda (a b) (+ a (random (- b a) state))) lo hi)))
             (let* ((targets (loop repeat n collect (chain-fk c (draw))))
                    (seeds (loop repeat n collect (draw)))
                    (results (make-array n))
                    (t0 (wall-seconds)))
               (loop for k from 0 for target in targets for seed in seeds
                     do (setf (aref results k)
                              (multiple-value-list (chain-ik c target :seed seed :random-seed (1+ k)))))
               (let ((mean (/ (- (wall-seconds) t0) n))
                     (peer (cdr (assoc (format nil "kdl-mean:~a" tip) peers :test #'string=)))
                     (peer-solved (cdr (assoc (format nil "kdl-solved:~a" tip) peers :test #'string=))))
                 (loop for (sol err) across results
                       when sol
                         do (incf solved)
                            (setf worst-pos (max worst-pos (aref err 0))
                                  worst-rot (max worst-rot (aref err 1))))
                 (let ((*read-default-float-format* 'double-float))
                   (cram-bench:add-row
                    (format nil "native: PR2 ~a arm IK (~d random reachable poses, random seeds)" side n)
                    (format nil "~a, ~,1f% solved, worst ~,1e m ~,1e rad" (cram-bench:format-seconds mean)
                            (* 100 (/ solved n)) worst-pos worst-rot)
                    :peer-name (and peer "KDL LMA, 100 it x 200 restarts")
                    :peer (and peer (format nil "~a, ~,1f% solved" (cram-bench:format-seconds peer)
                                            (* 100 (or peer-solved 0))))
                    :ratio (and peer (/ mean peer))
                    :goal "<= 300 µs, >= 99%"
                    :met (and (<= mean 300d-6) (>= (/ solved n) 0.99))))))))
      (destroy-chain c))))

(defun ik-rows ()
  "The IK rows of the native benchmark (both PR2 arms)."
  (when (probe-file *ik-urdf*)
    (add-search-dir *shared-models*)
    (let ((peers (ik-peer-times)))
      (with-world (w)
        (let ((r (add-urdf w (uiop:read-file-string *ik-urdf*))))
          (ik-arm-row w r "left" "l_wrist_roll_link" peers)
          (ik-arm-row w r "right" "r_wrist_roll_link" peers))))))

(defparameter *bench-dir* (make-pathname :name nil :type nil :defaults *load-truename*)
  "The directory of the benchmark files.")

(defun teleport-time (w boxes)
  "Seconds per call of SET-OBJECT-POSE in the scene of BUILD-SCENE: the fastest of 5 batches
for each of 8 of its BOXES, then the median over those bodies (the time depends on where a body
lies in memory)."
  (let ((i 0))
    (declare (type fixnum i))
    (median (loop for k below 8
                  collect (let* ((body (nth (* 4 k) boxes))
                                 (home (object-pose w body))
                                 (pose (make-array 7 :element-type 'double-float
                                                     :initial-contents '(1d0 0d0 1d0 0d0 0d0 0d0 1d0))))
                            (declare (type (simple-array double-float (7)) pose))
                            (prog1 (cram-bench:time-per-call
                                    (lambda ()
                                      (declare (optimize speed))
                                      (setf (aref pose 0) (+ 1d0 (* 1d-6 (mod (setf i (logand (1+ i) #xffffff)) 100))))
                                      (set-object-pose w body pose))
                                    :best t :min-seconds 0.05d0)
                              (set-object-pose w body home)))))))

(defun print-teleport-time ()
  "Print \"teleport SECONDS\" measured in a fresh scene (the probe of another process)."
  (multiple-value-bind (w r boxes) (build-scene)
    (declare (ignore r))
    (format t "~&teleport ~,12f~%" (teleport-time w boxes))
    (destroy-world w)))

(defun teleport-rounds ()
  "The teleport row's times, ours and the raw program's, as two values: each the median over
*PROCESSES* fresh processes, measured in interleaved rounds (a process of the raw program, then
one of ours, in each round); NIL for a side that could not run."
  (let ((ours '()) (raw '())
        (raw-exe (namestring (merge-pathnames "build/raw_bench" *native-dir*))))
    (flet ((teleport-of (out)
             (and out (cdr (assoc "teleport" (parse-times out) :test #'string=)))))
      (dotimes (k *processes*)
        (let ((r (teleport-of (cram-bench:run-peer raw-exe "teleport"))))
          (when r (push r raw)))
        (let ((o (teleport-of
                  (cram-bench:run-peer
                   "sbcl" "--noinform" "--non-interactive" "--no-userinit"
                   "--eval" "(require :asdf)"
                   "--load" (namestring (merge-pathnames "bench-lib.lisp" *bench-dir*))
                   "--load" (namestring (merge-pathnames "native-bench.lisp" *bench-dir*))
                   "--eval" "(cram-native-bench::print-teleport-time)"))))
          (when o (push o ours)))))
    (values (and ours (median ours)) (and raw (median raw)))))

(cram-bench:define-benchmark native ()
  (let ((raw (raw-times)))
    (multiple-value-bind (w r boxes) (build-scene)
      (unwind-protect
           (let* ((b (nth 5 boxes))
                  (pose (make-array 7 :element-type 'double-float :initial-contents '(1d0 0d0 1d0 0d0 0d0 0d0 1d0)))
                  (joints (make-array 45 :element-type '(signed-byte 32)))
                  (values (make-array 45 :element-type 'double-float))
                  (poses (make-array (* 7 46) :element-type 'double-float))
                  (i 0))
             (declare (type fixnum i) (type (simple-array double-float (7)) pose))
             (dotimes (k 45) (setf (aref joints k) k))
             (multiple-value-bind (ours peer) (teleport-rounds)
               (let ((ours (or ours (teleport-time w boxes)))
                     (raw (if peer
                              (acons "teleport" peer (remove "teleport" raw :key #'car
                                                                             :test #'string=))
                              raw)))
                 (anchor "native: teleport a body (median of 8 bodies, 3 processes)"
                         (row "native: teleport a body (median of 8 bodies, 3 processes)"
                              ours "teleport" raw)
                         1d-6)))
             (row "native: teleport a body, then its contacts"
                  (cram-bench:time-per-call
                   (lambda ()
                     (declare (optimize speed) (type fixnum i))
                     (setf (aref pose 0) (+ 1.6d0 (* 1d-3 (logand (setf i (logand (1+ i) #xffffff)) 1)))
                           (aref pose 1) -0.8d0 (aref pose 2) 0.05d0)
                     (set-object-pose w b pose)
                     (object-contacts w b))
                   :best t)
                  "teleport-contacts" raw :goal-ratio nil)
             (set-object-pose w b '(1.6 -0.8 0.05 0 0 0 1))
             (row "native: set 45 joints + read link poses"
                  (cram-bench:time-per-call
                   (lambda () (incf i)
                     (dotimes (k 45) (setf (aref values k) (* 0.01d0 (mod (+ i k) 20))))
                     (set-robot-joints w r joints values)
                     (robot-link-poses w r poses))
                   :best t)
                  "joints-and-poses" raw)
             (anchor "native: robot vs world collision check"
                     (row "native: robot vs world collision check"
                          (cram-bench:time-per-call (lambda () (object-contacts w r)) :best t)
                          "robot-collision" raw)
                     140d-6)
             (row "native: set 45 joints, then robot collision check"
                  (cram-bench:time-per-call
                   (lambda () (incf i)
                     (dotimes (k 45) (setf (aref values k) (* 0.01d0 (mod (+ i k) 20))))
                     (set-robot-joints w r joints values)
                     (object-contacts w r))
                   :best t)
                  "joints-collision" raw :goal-ratio nil)
             (row "native: copy world (34 bodies + 45-link robot)"
                  (cram-bench:time-per-call (lambda () (destroy-world (copy-world w))) :best t)
                  "copy" raw :goal-ratio nil :goal-abs 1d-3)
             (anchor "native: simulate 1 s, 34 bodies, 240 Hz" (row "native: simulate 1 s, 34 bodies, 240 Hz"
                  (cram-bench:median-seconds
                   (lambda ()
                     (with-world (s)
                       (add-plane s)
                       (dotimes (k 33)
                         (add-box s (list (* 0.3 (mod k 6)) (* 0.3 (floor k 6)) (+ 0.3 (* 0.12 (mod k 3))) 0 0 0 1)
                                  '(0.1 0.1 0.1) :mass 1))
                       (simulate s 1 (/ 1d0 240))))
                   :runs 5 :best t)
                  "simulate" raw) 127d-3)
             (let ((cam (look-at '(0 0 1.2) (subseq (object-pose w b) 0 3))))
               (row "native: visibility query (128x96)"
                    (cram-bench:time-per-call (lambda () (visibility w cam b)))
                    "visibility" raw :goal-ratio nil :goal-abs 1d-3)
               (let ((png (format nil "/tmp/cram-native-bench-~d.png" (sb-posix:getpid))))
                 (anchor "native: render 320x240 PNG" (row "native: render 320x240 PNG"
                      (cram-bench:time-per-call (lambda () (render-png w cam png :width 320 :height 240))
                                                :runs 3)
                      "png" raw :goal-ratio nil) 55d-3)
                 (ignore-errors (delete-file png)))))
        (destroy-world w)))
    (ik-rows)))
