;;;; cram-native: contacts, distances, rays and attachments.

(in-package :cram-native)

(defcn "cn_world_contacts" :int (w :int) (th :double) (o4 :pointer) (d :pointer) (cap :int))
(defcn "cn_object_contacts" :int (w :int) (o :int) (th :double) (o4 :pointer) (d :pointer)
  (cap :int))
(defcn "cn_object_contacts_except" :int (w :int) (o :int) (th :double) (ex :pointer) (n :int)
  (o4 :pointer) (d :pointer) (cap :int))
(defcn "cn_object_first_contact" :int (w :int) (o :int) (th :double) (ex :pointer) (n :int)
  (skip :pointer) (nskip :int) (allowed :pointer) (nallowed :int) (o4 :pointer))
(defcn "cn_closest_distance" :int (w :int) (a :int) (la :int) (b :int) (lb :int) (maxd :double)
  (out :pointer))
(defcn "cn_ignore_pair" :int (w :int) (a :int) (la :int) (b :int) (lb :int) (ignore :int))
(defcn "cn_ray_test" :int (w :int) (from :pointer) (to :pointer) (n :int) (hit :pointer)
  (out :pointer))
(defcn "cn_attach" :int (w :int) (o :int) (p :int) (l :int) (loose :int))
(defcn "cn_detach" :int (w :int) (o :int) (p :int))
(defcn "cn_attachments" :int (w :int) (out :pointer) (cap :int))
(defcn "cn_set_contact_prefilter" :int (on :int))

(defvar *pair-capacity* 256 "Smallest heap capacity of the contact pair buffers when 8 pairs do not suffice.")

(defun %pairs-list (iv dv n)
  (loop for i below n
        collect (list (aref iv (* 4 i)) (aref iv (+ 1 (* 4 i)))
                      (aref iv (+ 2 (* 4 i))) (aref iv (+ 3 (* 4 i)))
                      (aref dv i))))

(defun %collect-pairs (fn)
  "Call FN with (ints doubles cap) until the buffers are large enough; return a list of
(obj-a link-a obj-b link-b distance).  The first try uses buffers on the stack."
  (flet ((try (iv dv cap)
           (let ((n (with-vector-pointers ((pi4 iv) (pd dv)) (funcall fn pi4 pd cap))))
             (values (and (<= n cap) (%pairs-list iv dv n)) n))))
    (let ((iv (make-array (* 4 8) :element-type '(signed-byte 32)))
          (dv (make-array 8 :element-type 'double-float)))
      (declare (dynamic-extent iv dv))
      (multiple-value-bind (pairs n) (try iv dv 8)
        (if (<= n 8)
            pairs
            (loop for cap = (max n *pair-capacity*) then n
                  do (multiple-value-bind (pairs m)
                         (try (make-array (* 4 cap) :element-type '(signed-byte 32)) (make-dvec cap) cap)
                       (when (<= m cap) (return pairs))
                       (setf n m))))))))

(defun world-contacts (world &key (threshold 0d0))
  "Every pair of objects of WORLD whose closest distance is <= THRESHOLD (0: touching or
penetrating), as a list of (object-a link-a object-b link-b distance); links are -1 for
plain bodies.  Ignored pairs and filtered groups are left out."
  (let ((th (real-arg threshold 'world-contacts "threshold")))
    (%collect-pairs (lambda (pi4 pd cap) (ccall "cn_world_contacts" world th pi4 pd cap)))))

(defun set-contact-prefilter (on)
  "Whether OBJECT-CONTACTS and OBJECT-FIRST-CONTACT of an articulated object leave out, without
asking Bullet's contact query, the link pairs that a GJK distance (never more than the distance)
proves more than the threshold plus 1 mm apart: true (the default) or NIL, for comparisons: the
answers are the same either way. Returns the setting before."
  (= 1 (ccall "cn_set_contact_prefilter" (if on 1 0))))

(defun object-contacts (world object &key (threshold 0d0) except)
  "Contacts of OBJECT (all links of an articulated object) with every other object but those
of EXCEPT (a list of object handles, whose contacts are not looked for), as a list of (object
link other other-link distance)."
  (let ((th (real-arg threshold 'object-contacts "threshold")))
    (if except
        (let ((ex (make-array (length except) :element-type '(signed-byte 32))))
          (loop for h in except for i from 0
                do (setf (aref ex i) (int-arg h 'object-contacts "object to leave out")))
          (%collect-pairs (lambda (pi4 pd cap)
                            (with-vector-pointers ((pex ex))
                              (ccall "cn_object_contacts_except" world object th pex (length ex)
                                     pi4 pd cap)))))
        (%collect-pairs (lambda (pi4 pd cap)
                          (ccall "cn_object_contacts" world object th pi4 pd cap))))))

(defun fill-int-vector (v values what &optional (start 0))
  "Store VALUES (a list of integers, :ANY as -2) into the 32-bit integer vector V from START;
WHAT names them in an error. Returns the index after the last."
  (declare (type (simple-array (signed-byte 32) (*)) v) (type fixnum start))
  (dolist (x values start)
    (setf (aref v start) (if (eq x :any) -2 (int-arg x 'object-first-contact what)))
    (incf start)))

(defun object-first-contact (world object &key (threshold 0d0) except skip-links allowed)
  "The first contact of the articulated OBJECT's links with another object (or of two of its
links, when its self-collision is on) that is not left out, as (object link other other-link),
or NIL when there is none: a yes/no collision check that stops at the first contact. Left out:
the objects of EXCEPT (handles), the links of OBJECT in SKIP-LINKS (indices) and the contacts
ALLOWED covers, a list of (link other other-link) with :ANY for any."
  (unless (every (lambda (triple) (and (listp triple) (= 3 (length triple)))) allowed)
    (error "OBJECT-FIRST-CONTACT: allowed contacts ~s: expected a list of (link other other-link)."
           allowed))
  (let* ((th (real-arg threshold 'object-first-contact "threshold"))
         (nex (length except)) (nskip (length skip-links)) (nal (* 3 (length allowed)))
         (out (make-array 4 :element-type '(signed-byte 32))))
    (declare (dynamic-extent out))
    ;; the three lists one after the other
    (with-scratch-vector (v (+ nex nskip nal) (signed-byte 32) 4096)
      (fill-int-vector v except "object to leave out")
      (fill-int-vector v skip-links "link to leave out" nex)
      (let ((i (+ nex nskip)))
        (dolist (triple allowed) (setf i (fill-int-vector v triple "allowed contact" i))))
      (when (= 1 (with-vector-pointers ((pv v) (pout out))
                   (ccall "cn_object_first_contact" world object th
                          pv nex (sb-sys:sap+ pv (* 4 nex)) nskip
                          (sb-sys:sap+ pv (* 4 (+ nex nskip))) (floor nal 3) pout)))
        (list (aref out 0) (aref out 1) (aref out 2) (aref out 3))))))

(defun closest-distance (world object-a object-b &key (link-a -1) (link-b -1) (max-distance 1d0))
  "Closest distance between OBJECT-A and OBJECT-B (or the given links), searched up to
MAX-DISTANCE.  Returns the distance (negative = penetration, MAX-DISTANCE when nothing is that
close), the point on A and the point on B (DVECs of 3), and whether a pair was found."
  (let* ((v (make-dvec 7))
         (found (with-vector-pointers ((p v))
                  (ccall "cn_closest_distance" world object-a link-a object-b link-b
                         (real-arg max-distance 'closest-distance "max distance") p))))
    (values (aref v 0) (subseq v 1 4) (subseq v 4 7) (= found 1))))

(defun ignore-pair (world object-a object-b &key (link-a -1) (link-b -1) (ignore t))
  "Leave the pair out of contacts and physics (IGNORE true) or take it back in.
Links -1 mean the whole object."
  (ccall "cn_ignore_pair" world object-a link-a object-b link-b (if ignore 1 0))
  ignore)

(defun ray-test (world from to)
  "Cast rays FROM[i] -> TO[i].  FROM and TO are lists of (x y z) or flat DVECs of 3n.
Returns a list with one entry per ray: NIL for no hit, or (object link fraction point normal)."
  (flet ((flat (x what)
           (if (typep x 'dvec) x
               (to-dvec (loop for p in (coerce x 'list) append (coerce p 'list)) nil 'ray-test what))))
    (let* ((f (flat from "ray starts")) (g (flat to "ray ends"))
           (n (floor (length f) 3)))
      (unless (and (= (length f) (length g)) (zerop (mod (length f) 3)))
        (arg-error 'ray-test "~d start and ~d end coordinates, expected equal multiples of 3"
                   (length f) (length g)))
      (let ((hits (make-array (* 2 n) :element-type '(signed-byte 32)))
            (out (make-dvec (* 7 n))))
        (with-vector-pointers ((pf f) (pg g) (ph hits) (po out))
          (ccall "cn_ray_test" world pf pg n ph po))
        (loop for i below n
              collect (and (>= (aref hits (* 2 i)) 0)
                           (list (aref hits (* 2 i)) (aref hits (1+ (* 2 i)))
                                 (aref out (* 7 i))
                                 (subseq out (+ 1 (* 7 i)) (+ 4 (* 7 i)))
                                 (subseq out (+ 4 (* 7 i)) (+ 7 (* 7 i))))))))))

(defun ray-hit-objects (world from to)
  "Cast rays FROM[i] -> TO[i] as RAY-TEST does, FROM and TO flat DVECs of 3n; a vector of n
\(signed-byte 32), the handle of the object each ray hits first, -1 where it hits nothing.
For many rays whose hit points and normals nobody asks for (line-of-sight tests)."
  (unless (and (typep from 'dvec) (typep to 'dvec) (= (length from) (length to))
               (zerop (mod (length from) 3)))
    (arg-error 'ray-hit-objects "ray starts ~s and ends ~s, expected double-float vectors of ~
                                 equal length, a multiple of 3" from to))
  (let* ((n (floor (length from) 3))
         (objects (make-array n :element-type '(signed-byte 32))))
    (when (plusp n)
      (let ((hits (make-array (* 2 n) :element-type '(signed-byte 32)))
            (out (make-dvec (* 7 n))))
        (with-vector-pointers ((pf from) (pg to) (ph hits) (po out))
          (ccall "cn_ray_test" world pf pg n ph po))
        (dotimes (i n) (setf (aref objects i) (aref hits (* 2 i))))))
    objects))

(defun attach (world object parent &key (link -1) loose)
  "Attach body OBJECT to PARENT (LINK of an articulated object, or a body with LINK -1).
Rigid (LOOSE nil): OBJECT keeps its pose relative to the link and follows it; loose: only
recorded."
  (ccall "cn_attach" world object parent link (if loose 1 0))
  t)

(defun detach (world object &optional (parent -1))
  "Detach OBJECT from PARENT (-1: from everything); return the number of attachments removed."
  (ccall "cn_detach" world object parent))

(defun attachments (world)
  "Every attachment of WORLD as a list of (object parent link loose-p)."
  (let* ((n (ccall "cn_attachments" world (cffi:null-pointer) 0))
         (v (make-array (max 1 (* 4 n)) :element-type '(signed-byte 32))))
    (with-vector-pointers ((p v)) (ccall "cn_attachments" world p n))
    (loop for i below n
          collect (list (aref v (* 4 i)) (aref v (+ 1 (* 4 i))) (aref v (+ 2 (* 4 i)))
                        (= 1 (aref v (+ 3 (* 4 i))))))))
