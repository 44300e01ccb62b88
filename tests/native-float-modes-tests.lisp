;;;; Tests of cram-native: the caller's floating point modes, the unmasked teleport path, the
;;;; bounding boxes brought up to date at the next query, and meshes as one hull or one per part.

(in-package :cram-native-tests)
(in-suite native)

(defun trap-list ()
  "The floating point traps enabled in this thread."
  (getf (sb-int:get-floating-point-modes) :traps))

(defun divide (a b)
  "A / B at run time (the compiler does not fold it)."
  (/ a b))

(test shim-calls-keep-lisp-float-traps
  "Every kind of call (fast teleport, masked teleport, physics, queries, rendering, IK) leaves
SBCL's traps as they were: a division by zero still signals afterwards."
  (let ((before (trap-list)))
    (is (member :divide-by-zero before))
    (with-world (w)
      (add-plane w)
      (let ((b (add-box w '(0 0 1 0 0 0 1) '(0.1 0.1 0.1) :mass 1))
            (r (add-urdf w *arm-urdf* :pose '(-1 0 0 0 0 0 1))))
        (set-object-pose w b '(0 0 0.5 0 0 0 1))
        (is (equal before (trap-list)))
        (set-object-pose w b '(0 0 1d150 0 0 0 1)) ; masked path
        (is (equal before (trap-list)))
        (set-object-pose w b '(0 0 0.5 0 0 0 1))
        (simulate w 0.2 (/ 1d0 240))
        (object-contacts w b)
        (world-contacts w)
        (ray-test w '((0 0 3)) '((0 0 -1)))
        (set-robot-joints w r '(0 1) '(0.3 0.2))
        (visibility w (look-at '(2 0 1) '(0 0 0.3)) b)
        (is (equal before (trap-list)))))
    (signals division-by-zero (divide 1d0 0d0))))

(test teleport-paths-agree
  "A tame pose (unmasked path) and poses the masked path takes (tiny or huge components, a
body carrying an attachment) give the same normalised result."
  (with-world (w)
    (let ((a (add-box w '(0 0 0 0 0 0 1) '(0.1 0.1 0.1) :mass 1))
          (b (add-box w '(0 0 0 0 0 0 1) '(0.1 0.1 0.1) :mass 1)))
      ;; the same rotation, given once unnormalised and tame, once with a 1e-120 component
      (set-object-pose w a '(1 2 3 0 0 2 2))
      (set-object-pose w b '(1 2 3 1d-120 0 2 2))
      (let ((pa (object-pose w a)) (pb (object-pose w b)))
        (is (every (lambda (x y) (approx x y 1d-12)) pa pb))
        (is (approx (/ (sqrt 2d0) 2) (aref pa 6) 1d-12)))
      ;; a body carrying another moves it along (masked path)
      (attach w b a)
      (set-object-pose w a '(5 0 0 0 0 0 1))
      (is (approx 5d0 (aref (object-pose w b) 0) 1d-9))
      (detach w b)
      (set-object-pose w a '(7 0 0 0 0 0 1))
      (is (approx 5d0 (aref (object-pose w b) 0) 1d-9))
      ;; a zero quaternion is refused on the fast path with its value named
      (signals-naming ("zero quaternion") (set-object-pose w a '(0 0 0 0 0 0 0)))
      (is (approx 7d0 (aref (object-pose w a) 0) 1d-12))
      ;; NaN and infinite components are refused, naming them, and raise no trap on the way
      (signals-naming ("NaN") (set-object-pose w a (list 0 (nan) 0 0 0 0 1)))
      (signals-naming ("infinity")
        (set-object-pose w a (list 0 0 sb-ext:double-float-positive-infinity 0 0 0 1))))))

(test queries-see-teleported-bodies
  "Bounding boxes are brought up to date at the next query: after many teleports without a
query, contacts, rays, distances and physics see each body where it is now."
  (with-world (w)
    (let ((plane (add-plane w))
          (m (add-box w '(0 0 0.1 0 0 0 1) '(0.2 0.2 0.2) :mass 1))
          (wall (add-box w '(5 0 0.5 0 0 0 1) '(0.2 2 1))))
      (dotimes (k 100) (set-object-pose w m (list (* 0.01 k) 3 0.1 0 0 0 1)))
      (set-object-pose w m '(5.15 0 0.5 0 0 0 1))         ; into the wall
      (is (find wall (object-contacts w m) :key #'third))
      (is (null (first (first (ray-test w '((0 0 3)) '((0 0 0.3))))))) ; old place is empty
      (is (eql m (first (first (ray-test w '((5.2 0 3)) '((5.2 0 0.45)))))))
      (is (find-if (lambda (p) (or (and (eql (first p) m) (eql (third p) wall))
                                   (and (eql (first p) wall) (eql (third p) m))))
                   (world-contacts w)))
      (set-object-pose w m '(-3 0 0.1 0 0 0 1))
      (is (not (find wall (object-contacts w m) :key #'third)))
      (is (< (closest-distance w m wall :max-distance 10) 8.1))
      ;; dropped after teleports, it lands on the floor (the plane sees it)
      (set-object-pose w m '(-3 0 1 0 0 0 1))
      (simulate w 2 (/ 1d0 240))
      (is (approx 0.1d0 (aref (object-pose w m) 2) 3d-3))
      (is (find plane (object-contacts w m :threshold 1d-3) :key #'third))
      ;; teleported, then removed before any query: the next queries run cleanly
      (let ((n (add-box w '(9 9 0.5 0 0 0 1) '(0.2 0.2 0.2))))
        (set-object-pose w n '(8 8 0.5 0 0 0 1))
        (remove-object w n))
      (is (listp (world-contacts w)))
      (is (null (first (first (ray-test w '((8 8 3)) '((8 8 0.3))))))))))

(test robot-contacts-agree-with-world-contacts
  "The contacts of an articulated object (one broadphase query for all its links) are the
pairs the whole-world collision pass finds for it: 20 seeded random scenes and arm poses."
  (let ((state (sb-ext:seed-random-state 11)) (checked 0))
    (dotimes (scene 20)
      (with-world (w)
        (let ((r (add-urdf w *arm-urdf*)))
          (dotimes (k 25)
            (add-sphere w (list (- (random 1.4d0 state) 0.7d0) (- (random 1.4d0 state) 0.7d0)
                                (random 1.2d0 state) 0 0 0 1)
                        (+ 0.03d0 (random 0.08d0 state))))
          (set-robot-joints w r '(0 1) (list (- (random 6d0 state) 3d0) (- (random 4d0 state) 2d0)))
          (flet ((with-r (pairs limit)
                   ;; (link other) of the pairs with r closer than LIMIT
                   (loop for (a la b lb d) in pairs
                         when (and (< d limit) (or (eql a r) (eql b r)) (not (eql a b)))
                           collect (if (eql a r) (list la b) (list lb a)))))
            (let ((ours (object-contacts w r :threshold 1d-3))
                  (all (world-contacts w :threshold 1d-3)))
              ;; every clearly penetrating pair of one is a contact of the other
              (dolist (p (with-r all -2d-3))
                (incf checked)
                (is (member p (with-r ours 2d-3) :test #'equal)))
              (dolist (p (with-r ours -2d-3))
                (is (member p (with-r all 2d-3) :test #'equal))))))))
    (is (> checked 5) "only ~d penetrating pairs over all scenes" checked)))

(test simulate-stops-early-only-when-nothing-moves
  "SIMULATE skips the steps after every dynamic body has come to rest: a dropped box ends where
single steps put it, and a box balanced past its edge still falls over."
  (flet ((drop-box (stepper)
           (with-world (w)
             (add-plane w)
             (let ((b (add-box w '(0 0 0.6 0 0 0 1) '(0.1 0.1 0.1) :mass 1)))
               (funcall stepper w)
               (coerce (object-pose w b) 'list)))))
    (let ((early (drop-box (lambda (w) (simulate w 3 0.01d0))))
          (every-step (drop-box (lambda (w) (dotimes (i 300) (step-world w 0.01d0))))))
      (is (< (abs (- (third early) 0.05d0)) 2d-3) "the box does not rest on the floor: ~a" early)
      (is (< (sqrt (reduce #'+ (mapcar (lambda (a b) (expt (- a b) 2))
                                       (subseq early 0 3) (subseq every-step 0 3))))
             1d-3)
          "early stop ~a, every step ~a" early every-step)))
  (with-world (w)
    (add-plane w)
    ;; a tall box on a narrow ledge, its centre 1 cm beyond the ledge's edge, starts at rest
    (add-box w '(0 0 0.25 0 0 0 1) '(0.2 0.2 0.5))
    (let ((tall (add-box w '(0.11 0 0.7 0 0 0 1) '(0.04 0.04 0.4) :mass 1)))
      (simulate w 3 0.01d0)
      (is (< (aref (object-pose w tall) 2) 0.5d0) "the box did not fall: ~a" (object-pose w tall)))))

(defun write-two-cubes-obj (path)
  "Write to PATH an OBJ file of two 0.2 m cubes as two objects, 0.2 m apart along x (the gap
from x -0.1 to 0.1), bottoms at z 0. Returns PATH."
  (with-open-file (s path :direction :output :if-exists :supersede)
    (loop for x0 in '(-0.3 0.1) for part from 0
          do (format s "o cube~d~%" part)
             (dotimes (i 8)
               (format s "v ~f ~f ~f~%" (+ x0 (* 0.2 (ldb (byte 1 0) i)))
                       (+ -0.1 (* 0.2 (ldb (byte 1 1) i))) (* 0.2 (ldb (byte 1 2) i))))
             (loop for (a b c d) in '((1 3 4 2) (5 6 8 7) (1 2 6 5) (3 7 8 4) (1 5 7 3) (2 4 8 6))
                   do (format s "f ~{~d~^ ~}~%" (mapcar (lambda (k) (+ k (* 8 part))) (list a b c d))))))
  path)

(defun probe-in-gap-touches-p (w object)
  "Does a movable 0.1 m cube put into the middle of the gap of the two-cube mesh touch OBJECT?"
  (let ((probe (add-box w '(0 0 0.1 0 0 0 1) '(0.1 0.1 0.1) :mass 1)))
    (prog1 (and (find object (object-contacts w probe) :key #'third) t)
      (remove-object w probe))))

(test mesh-as-one-hull-or-one-hull-per-part
  "ADD-MESH gives one convex hull per part of a two-part mesh (its gap stays free), with
:SINGLE-HULL one hull around both parts (the gap is filled), movable or static; ADD-URDF's
:SINGLE-HULL does the same to link meshes, and cannot go with :EXACT-MESHES."
  (let ((path (write-two-cubes-obj (concatenate 'string (temp-dir) "two-cubes.obj"))))
    (with-world (w)
      (dolist (mass '(1 0))
        (let ((parts (add-mesh w '(0 0 0 0 0 0 1) path :mass mass))
              (one (add-mesh w '(2 0 0 0 0 0 1) path :mass mass :single-hull t)))
          (is (not (probe-in-gap-touches-p w parts)) "mass ~a: the gap of the parts is filled" mass)
          (set-object-pose w one '(0 0 0 0 0 0 1))
          (remove-object w parts)
          (is (probe-in-gap-touches-p w one) "mass ~a: the single hull leaves the gap free" mass)
          (is (eq :mesh (body-shape w one)))
          (remove-object w one)))
      (let* ((urdf (format nil "<robot name='two'><link name='a'><collision><geometry><mesh filename='~a'/></geometry></collision></link></robot>" path))
             (parts (add-urdf w urdf)))
        (is (not (probe-in-gap-touches-p w parts)))
        (remove-object w parts)
        (let ((one (add-urdf w urdf :single-hull t)))
          (is (probe-in-gap-touches-p w one))
          (remove-object w one))
        (signals-naming (":exact-meshes T" ":single-hull :YES" "exclude each other")
          (add-urdf w urdf :exact-meshes t :single-hull :yes))))))
