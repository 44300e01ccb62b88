;;;; cram-native: sweep checks, what a robot or a body passes through between two poses
;;;; (cn_robot_sweep_check, cn_body_sweep_check).

(in-package :cram-native)

(export '(robot-sweep-check body-sweep-check robot-sweep-paths *sweep-max-step* *sweep-tolerance*))

(defcn "cn_robot_sweep_check" :int (w :int) (r :int) (b0 :pointer) (q0 :pointer) (b1 :pointer)
  (q1 :pointer) (nq :int) (ign :pointer) (nign :int) (step :double) (tol :double) (flags :int)
  (o4 :pointer) (od :pointer) (cap :int))
(defcn "cn_body_sweep_check" :int (w :int) (b :int) (p0 :pointer) (p1 :pointer) (ign :pointer)
  (nign :int) (step :double) (tol :double) (flags :int) (o4 :pointer) (od :pointer) (cap :int))

(defcn "cn_robot_sweep_paths" :int (w :int) (r :int) (b0 :pointer) (q0 :pointer) (b1 :pointer)
  (q1 :pointer) (nq :int) (frames :pointer) (nframes :int) (steps :int) (out :pointer))

(defvar *sweep-max-step* 0.05d0
  "Largest summed joint rotation (rad) and translation (m) of one sub-step of a sweep check.")

(defvar *sweep-tolerance* 1d-3
  "Depth (m) below which a sweep check may miss a contact; it never reports a pair whose
distance stays above 0.")

(defun %ignore-vector (ignore function)
  "IGNORE, a list of (moving-object moving-link hit-object hit-link) with -1 for any, as an
IVEC of 4 per record."
  (unless (and (listp ignore)
               (every (lambda (r) (and (listp r) (= (length r) 4)
                                       (every (lambda (v) (typep v '(signed-byte 32))) r)))
                      ignore))
    (arg-error function "ignore list ~s, expected a list of (moving-object moving-link ~
                         hit-object hit-link) integers, -1 for any" ignore))
  (let ((v (make-array (max 1 (* 4 (length ignore))) :element-type '(signed-byte 32)
                                                     :initial-element -1)))
    (loop for r in ignore for i from 0
          do (loop for x in r for k from 0 do (setf (aref v (+ (* 4 i) k)) x)))
    v))

(defparameter *sweep-record-capacity* 128
  "How many records the first call of a sweep check has room for: a check that reports more
runs again with room for all of them (the household's checks report up to about a hundred).")

(defun %sweep-records (fn)
  "Call FN with (ints doubles cap) until its records fit; return them as a list of
(moving-object moving-link hit-object hit-link fraction point), POINT a DVEC of 3. The first
call's buffers are on the stack when *SWEEP-RECORD-CAPACITY* is at most 128."
  (flet ((try (iv dv cap)
           (declare (type (simple-array (signed-byte 32) (*)) iv) (type dvec dv) (type fixnum cap))
           (let ((n (with-vector-pointers ((pi4 iv) (pd dv)) (funcall fn pi4 pd cap))))
             (values (and (<= n cap)
                          (loop for i below n
                                collect (list (aref iv (* 4 i)) (aref iv (+ 1 (* 4 i)))
                                              (aref iv (+ 2 (* 4 i))) (aref iv (+ 3 (* 4 i)))
                                              (aref dv (* 4 i))
                                              (subseq dv (+ 1 (* 4 i)) (+ 4 (* 4 i))))))
                     n))))
    (let ((cap *sweep-record-capacity*))
      (loop (multiple-value-bind (records n)
                (with-scratch-vector (iv (* 4 cap) (signed-byte 32) 512)
                  (with-scratch-vector (dv (* 4 cap) double-float 512)
                    (try iv dv cap)))
              (when (<= n cap) (return records))
              (setf cap n))))))

(defun %sweep-flags (skip-start-contacts &optional reference)
  (logior (if skip-start-contacts 1 0) (if reference 2 0)))

(defun robot-sweep-check (world robot base-from joints-from base-to joints-to
                          &key ignore (max-step *sweep-max-step*) (tolerance *sweep-tolerance*)
                            skip-start-contacts reference)
  "What ROBOT's links and rigidly attached objects pass through while its base moves on a
straight line from BASE-FROM to BASE-TO (poses as for SET-OBJECT-POSE) and its joints move
linearly from JOINTS-FROM to JOINTS-TO (every joint, index order, as ROBOT-JOINTS gives them).
The robot in WORLD is not moved. IGNORE lists (moving-object moving-link hit-object hit-link)
pairs not to report, -1 for any; SKIP-START-CONTACTS leaves out the pairs within TOLERANCE at
the start. Returns one list (moving-object moving-link hit-object hit-link fraction point) per
pair at its first contact, earliest first; links are -1 for bodies, FRACTION in [0, 1] of the
move, POINT a DVEC x y z. REFERENCE (for tests) runs the plain reference search, which gives the
same records more slowly."
  (let* ((f 'robot-sweep-check)
         (b0 (pose-vec base-from f "start base pose"))
         (b1 (pose-vec base-to f "end base pose"))
         (q0 (to-dvec joints-from nil f "start joint values"))
         (q1 (to-dvec joints-to nil f "end joint values"))
         (ign (%ignore-vector ignore f))
         (step (real-arg max-step f "maximum step"))
         (tol (real-arg tolerance f "tolerance")))
    (unless (= (length q0) (length q1))
      (arg-error f "~d start and ~d end joint values, expected as many" (length q0) (length q1)))
    (%sweep-records
     (lambda (o4 od cap)
       (with-vector-pointers ((pb0 b0) (pb1 b1) (pq0 q0) (pq1 q1) (pig ign))
         (ccall "cn_robot_sweep_check" (int-arg world f "world") (int-arg robot f "robot") pb0 pq0 pb1 pq1 (length q0) pig (length ignore)
                step tol (%sweep-flags skip-start-contacts reference) o4 od cap))))))

(defun body-sweep-check (world body from to &key ignore (max-step *sweep-max-step*)
                                                 (tolerance *sweep-tolerance*) skip-start-contacts)
  "What BODY (and the bodies rigidly attached to it) passes through moving from pose FROM to
pose TO (translation on a straight line, rotation by slerp); keys and result as
ROBOT-SWEEP-CHECK."
  (let* ((f 'body-sweep-check)
         (p0 (pose-vec from f "start pose"))
         (p1 (pose-vec to f "end pose"))
         (ign (%ignore-vector ignore f))
         (step (real-arg max-step f "maximum step"))
         (tol (real-arg tolerance f "tolerance")))
    (%sweep-records
     (lambda (o4 od cap)
       (with-vector-pointers ((pp0 p0) (pp1 p1) (pig ign))
         (ccall "cn_body_sweep_check" (int-arg world f "world") (int-arg body f "body") pp0 pp1 pig (length ignore) step tol
                (%sweep-flags skip-start-contacts) o4 od cap))))))

(defun robot-sweep-paths (world robot base-from joints-from base-to joints-to frames &key (steps 16))
  "Where the FRAMES (a list of (object link): (ROBOT link-index) for a link, (body -1) for a
body ROBOT carries rigidly) are along the motion ROBOT-SWEEP-CHECK checks from BASE-FROM and
JOINTS-FROM to BASE-TO and JOINTS-TO: their origins at the STEPS + 1 times 0, 1/STEPS .. 1, as
one DVEC of x y z per time, frame after frame. The world is not changed."
  (let* ((f 'robot-sweep-paths)
         (b0 (pose-vec base-from f "start base pose"))
         (b1 (pose-vec base-to f "end base pose"))
         (q0 (to-dvec joints-from nil f "start joint values"))
         (q1 (to-dvec joints-to nil f "end joint values"))
         (n (if (listp frames) (length frames) (arg-error f "frames ~s, expected a list of (object link)" frames)))
         (fv (make-array (max 1 (* 2 n)) :element-type '(signed-byte 32) :initial-element 0))
         (steps (int-arg steps f "steps"))
         (out (make-dvec (max 1 (* 3 n (1+ (max steps 0)))))))
    (unless (= (length q0) (length q1))
      (arg-error f "~d start and ~d end joint values, expected as many" (length q0) (length q1)))
    (loop for entry in frames for i from 0
          do (unless (and (listp entry) (= (length entry) 2)
                          (every (lambda (v) (typep v '(signed-byte 32))) entry))
               (arg-error f "frame ~s, expected (object link) integers" entry))
             (setf (aref fv (* 2 i)) (first entry) (aref fv (1+ (* 2 i))) (second entry)))
    (with-vector-pointers ((pb0 b0) (pb1 b1) (pq0 q0) (pq1 q1) (pf fv) (po out))
      (ccall "cn_robot_sweep_paths" (int-arg world f "world") (int-arg robot f "robot") pb0 pq0 pb1 pq1
             (length q0) pf n steps po))
    out))
