;;;; CL-URDF: a URDF model parsed with cxml into CLOS objects. The parsed robot keeps its XML
;;;; source, which is what the physics shim builds the articulated body from.

(in-package :cl-urdf)

(define-condition urdf-error (error)
  ((message :initarg :message :reader urdf-error-message))
  (:report (lambda (c s) (format s "URDF: ~a" (urdf-error-message c))))
  (:documentation "A URDF document that cannot be parsed or is inconsistent."))

(defun urdf-fail (fmt &rest args)
  (error 'urdf-error :message (apply #'format nil fmt args)))

(defclass robot ()
  ((name :initarg :name :reader name :documentation "The <robot name>.")
   (links :initarg :links :reader links :documentation "Hash table: link name → LINK.")
   (joints :initarg :joints :reader joints :documentation "Hash table: joint name → JOINT.")
   (root-link :initarg :root-link :accessor root-link :documentation "The LINK without parent.")
   (source :initarg :source :reader source :documentation "The URDF XML text.")
   (moved-joints :initarg :moved-joints :initform nil :reader moved-joints
                 :documentation "NIL, or (text . moves): this model is the one of the URDF text
TEXT with the <origin> attributes of some joints changed, MOVES a list of (joint-name xyz rpy)
of their texts (ROBOT-WITH-JOINT-ORIGINS :MOVED), from which the physics shim makes it without
parsing SOURCE."))
  (:documentation "A parsed URDF model."))

(defclass link ()
  ((name :initarg :name :reader name)
   (collision :initarg :collision :initform nil :reader collision
              :documentation "List of plists (:origin pose-list :geometry plist).")
   (visual :initarg :visual :initform nil :reader visual
           :documentation "List of plists (:origin :geometry :color).")
   (parent-joint :initform nil :accessor parent-joint)
   (child-joints :initform nil :accessor child-joints))
  (:documentation "A URDF link."))

(defclass joint ()
  ((name :initarg :name :reader name)
   (joint-type :initarg :type :reader joint-type :documentation "Keyword :revolute, :continuous,
:prismatic, :fixed, :floating or :planar.")
   (parent :initarg :parent :accessor parent :documentation "Parent LINK.")
   (child :initarg :child :accessor child :documentation "Child LINK.")
   (origin :initarg :origin :reader origin :documentation "((x y z) (qx qy qz qw)) of the child frame in the parent.")
   (axis :initarg :axis :reader axis :documentation "Unit axis (x y z) in the joint frame.")
   (limits :initarg :limits :initform nil :reader limits
           :documentation "Plist (:lower :upper :velocity :effort) or NIL.")
   (mimic :initarg :mimic :initform nil :reader mimic
          :documentation "Plist (:joint name :multiplier m :offset o) or NIL."))
  (:documentation "A URDF joint."))

(defmethod print-object ((r robot) s)
  (print-unreadable-object (r s :type t)
    (format s "~s (~d links, ~d joints)" (name r) (hash-table-count (links r))
            (hash-table-count (joints r)))))

(defmethod print-object ((l link) s)
  (print-unreadable-object (l s :type t) (format s "~s" (name l))))

(defmethod print-object ((j joint) s)
  (print-unreadable-object (j s :type t) (format s "~s ~s" (name j) (joint-type j))))

(defun lower (joint) "Lower limit of JOINT or NIL." (getf (limits joint) :lower))
(defun upper (joint) "Upper limit of JOINT or NIL." (getf (limits joint) :upper))

;;; ---- XML helpers -----------------------------------------------------------------------

(defun children-named (element tag)
  (loop for node across (dom:child-nodes element)
        when (and (dom:element-p node) (string= (dom:tag-name node) tag))
          collect node))

(defun child-named (element tag)
  (first (children-named element tag)))

(defun attr (element name &optional default)
  (if (and element (dom:has-attribute element name))
      (dom:get-attribute element name)
      default))

(defparameter *max-coordinate* 1d6
  "Largest magnitude (metres) of a coordinate in a URDF origin: larger ones are refused.")

(defparameter *max-length* 1d4
  "Largest magnitude (metres) of a URDF geometry's size, radius, length or scale.")

(defun numbers (string what &optional count max)
  "Parse the whitespace separated reals of STRING; with MAX, each must be at most MAX in
magnitude. Errors name STRING as written in the URDF."
  (let ((values '()) (start 0) (len (length string)))
    (loop
      (let ((b (position-if-not (lambda (c) (member c '(#\Space #\Tab #\Newline #\Return))) string :start start)))
        (unless b (return))
        (let* ((e (or (position-if (lambda (c) (member c '(#\Space #\Tab #\Newline #\Return))) string :start b) len))
               (token (subseq string b e))
               (v (let ((*read-default-float-format* 'double-float))
                    (handler-case (with-standard-io-syntax
                                    (let ((*read-default-float-format* 'double-float)
                                          (*read-eval* nil))
                                      (read-from-string token)))
                      (error () nil)))))
          (unless (realp v) (urdf-fail "~a: ~s is not a number (in ~s)" what token string))
          (when (and max (> (abs v) max))
            (urdf-fail "~a: ~s (in ~s) is beyond the bound ~g of its magnitude" what token string max))
          (push (coerce v 'double-float) values)
          (setf start e))))
    (setf values (nreverse values))
    (when (and count (/= (length values) count))
      (urdf-fail "~a: expected ~d numbers, got ~s" what count string))
    values))

(defun rpy->quaternion (r p y)
  "Quaternion (x y z w) of the fixed-axis roll R, pitch P, yaw Y."
  (let ((cr (cos (/ r 2))) (sr (sin (/ r 2))) (cp (cos (/ p 2))) (sp (sin (/ p 2)))
        (cy (cos (/ y 2))) (sy (sin (/ y 2))))
    (list (- (* sr cp cy) (* cr sp sy))
          (+ (* cr sp cy) (* sr cp sy))
          (- (* cr cp sy) (* sr sp cy))
          (+ (* cr cp cy) (* sr sp sy)))))

(defun text-origin (xyz rpy what)
  "The origin ((x y z) (qx qy qz qw)) of an <origin> element whose xyz and rpy attributes are
the texts XYZ and RPY (WHAT names its element in errors), as PARSE-URDF reads it."
  (list (numbers xyz (format nil "~a origin xyz" what) 3 *max-coordinate*)
        (apply #'rpy->quaternion (numbers rpy (format nil "~a origin rpy" what) 3))))

(defun parse-origin (element what)
  (if element
      (text-origin (attr element "xyz" "0 0 0") (attr element "rpy" "0 0 0") what)
      (list (list 0d0 0d0 0d0) (list 0d0 0d0 0d0 1d0))))

(defun parse-geometry (element what)
  (let ((g (and element (find-if #'dom:element-p (dom:child-nodes element)))))
    (unless g (urdf-fail "~a has no geometry" what))
    (let ((tag (dom:tag-name g)))
      (cond ((string= tag "box") (list :box :size (numbers (attr g "size" "") (format nil "~a box size" what) 3 *max-length*)))
            ((string= tag "cylinder")
             (list :cylinder :radius (first (numbers (attr g "radius" "") (format nil "~a radius" what) 1 *max-length*))
                             :length (first (numbers (attr g "length" "") (format nil "~a length" what) 1 *max-length*))))
            ((string= tag "sphere")
             (list :sphere :radius (first (numbers (attr g "radius" "") (format nil "~a radius" what) 1 *max-length*))))
            ((string= tag "mesh")
             (list :mesh :filename (or (attr g "filename") (urdf-fail "~a mesh without filename" what))
                         :scale (if (attr g "scale") (numbers (attr g "scale") (format nil "~a scale" what) 3 *max-length*)
                                    (list 1d0 1d0 1d0))))
            (t (urdf-fail "~a has unknown geometry <~a>" what tag))))))

(defun parse-link (element materials)
  (let* ((name (or (attr element "name") (urdf-fail "a <link> has no name")))
         (link (make-instance 'link :name name)))
    (setf (slot-value link 'collision)
          (mapcar (lambda (c) (list :origin (parse-origin (child-named c "origin") name)
                                    :geometry (parse-geometry (child-named c "geometry") name)))
                  (children-named element "collision"))
          (slot-value link 'visual)
          (mapcar (lambda (v)
                    (let* ((m (child-named v "material"))
                           (c (and m (child-named m "color"))))
                      (list :origin (parse-origin (child-named v "origin") name)
                            :geometry (parse-geometry (child-named v "geometry") name)
                            :color (cond (c (numbers (attr c "rgba" "") (format nil "~a color" name) 4))
                                         (m (gethash (attr m "name" "") materials))))))
                  (children-named element "visual")))
    link))

(defun parse-joint (element links)
  (let* ((name (or (attr element "name") (urdf-fail "a <joint> has no name")))
         (type (let ((ty (attr element "type")))
                 (cond ((member ty '("revolute" "continuous" "prismatic" "fixed" "floating" "planar")
                                :test #'equal)
                        (intern (string-upcase ty) :keyword))
                       (t (urdf-fail "joint ~s has type ~s, expected revolute, continuous, prismatic, fixed, floating or planar" name ty)))))
         (parent-name (attr (child-named element "parent") "link"))
         (child-name (attr (child-named element "child") "link"))
         (parent (or (gethash parent-name links) (urdf-fail "joint ~s names unknown parent link ~s" name parent-name)))
         (child (or (gethash child-name links) (urdf-fail "joint ~s names unknown child link ~s" name child-name)))
         (limit (child-named element "limit"))
         (mimic (child-named element "mimic"))
         (joint (make-instance
                 'joint :name name :type type :parent parent :child child
                 :origin (parse-origin (child-named element "origin") name)
                 :axis (if (child-named element "axis")
                           (let* ((text (attr (child-named element "axis") "xyz" "1 0 0"))
                                  (axis (numbers text (format nil "~a axis" name) 3 *max-coordinate*)))
                             (when (and (member type '(:revolute :continuous :prismatic))
                                        (every #'zerop axis))
                               (urdf-fail "joint ~s (~(~a~)): axis xyz ~s has zero length, ~
expected a direction" name type text))
                             axis)
                           (list 1d0 0d0 0d0))
                 :limits (and limit
                              (let ((lower (first (numbers (attr limit "lower" "0") name 1)))
                                    (upper (first (numbers (attr limit "upper" "0") name 1))))
                                (when (> lower upper)
                                  (urdf-fail "joint ~s: lower limit ~s is above upper limit ~s"
                                             name (attr limit "lower" "0") (attr limit "upper" "0")))
                                t)
                              (list :lower (first (numbers (attr limit "lower" "0") name 1))
                                    :upper (first (numbers (attr limit "upper" "0") name 1))
                                    :velocity (first (numbers (attr limit "velocity" "0") name 1))
                                    :effort (first (numbers (attr limit "effort" "0") name 1))))
                 :mimic (and mimic
                             (list :joint (attr mimic "joint")
                                   :multiplier (first (numbers (attr mimic "multiplier" "1") name 1))
                                   :offset (first (numbers (attr mimic "offset" "0") name 1)))))))
    (when (parent-joint child)
      (urdf-fail "link ~s has two parent joints: ~s and ~s" child-name (name (parent-joint child)) name))
    (setf (parent-joint child) joint)
    (push joint (child-joints parent))
    joint))

(defun joint-cycle-description (links)
  "A text naming the joints and links of a cycle among LINKS, all of which have a parent joint."
  (let* ((start (loop for l being the hash-values of links return l))
         (seen '()) (link start))
    ;; walk up the parents until a link repeats: that link lies on the cycle
    (loop until (member link seen) do (push link seen) (setf link (parent (parent-joint link))))
    (let ((cycle '()) (l link))
      (loop do (push (parent-joint l) cycle) (setf l (parent (parent-joint l)))
            until (eq l link))
      (format nil "~{joint ~s (~s -> ~s)~^, ~}"
              (loop for j in cycle collect (name j) collect (name (parent j)) collect (name (child j)))))))

(defun parse-urdf (xml)
  "Parse the URDF text XML (a string, or a pathname of a URDF file) into a ROBOT."
  (let* ((text (let ((text (typecase xml
                             ;; cxml reads a string of any element type, but not a BASE-STRING
                             ;; (what FORMAT NIL and PRINC-TO-STRING may return): copy it
                             (string (if (typep xml '(array character (*)))
                                         xml
                                         (coerce xml '(simple-array character (*)))))
                             (pathname (uiop:read-file-string xml))
                             (t (urdf-fail "expected the URDF text (a string) or a pathname, got ~s"
                                           xml)))))
                 (when (zerop (length (string-trim '(#\Space #\Tab #\Newline #\Return) text)))
                   (urdf-fail "the URDF text is empty (~s); expected a <robot> document" text))
                 text))
         (doc (handler-case (cxml:parse text (cxml-dom:make-dom-builder))
                (error (e) (urdf-fail "malformed XML: ~a" e))))
         (root (dom:document-element doc)))
    (unless (string= (dom:tag-name root) "robot")
      (urdf-fail "the document element is <~a>, expected <robot>" (dom:tag-name root)))
    (let ((materials (make-hash-table :test 'equal))
          (links (make-hash-table :test 'equal))
          (joints (make-hash-table :test 'equal)))
      (dolist (m (children-named root "material"))
        (let ((c (child-named m "color")))
          (when c (setf (gethash (attr m "name" "") materials)
                        (numbers (attr c "rgba" "") "material color" 4)))))
      (dolist (l (children-named root "link"))
        (let ((link (parse-link l materials)))
          (when (gethash (name link) links) (urdf-fail "link ~s is defined twice" (name link)))
          (setf (gethash (name link) links) link)))
      (dolist (j (children-named root "joint"))
        (let ((joint (parse-joint j links)))
          (setf (gethash (name joint) joints) joint)))
      (when (zerop (hash-table-count links)) (urdf-fail "the robot has no links"))
      (let ((roots (loop for l being the hash-values of links unless (parent-joint l) collect l)))
        (when (null roots)
          (urdf-fail "the joints form a cycle (every link has a parent joint): ~a"
                     (joint-cycle-description links)))
        (unless (= (length roots) 1)
          (urdf-fail "expected one root link, found ~d: ~{~s~^, ~}" (length roots) (mapcar #'name roots)))
        (make-instance 'robot :name (attr root "name" "") :links links :joints joints
                              :root-link (first roots) :source text)))))

(defun robot-link-names (robot)
  "Sorted names of the links of ROBOT."
  (sort (loop for k being the hash-keys of (links robot) collect k) #'string<))

(defun robot-joint-names (robot)
  "Sorted names of the joints of ROBOT."
  (sort (loop for k being the hash-keys of (joints robot) collect k) #'string<))

;;; ---- re-rooting ------------------------------------------------------------------------------

(defun quaternion-inverse-rotate (q v)
  "V rotated by the inverse of the unit quaternion Q (x y z w)."
  (destructuring-bind (qx qy qz qw) q
    (let* ((x (- qx)) (y (- qy)) (z (- qz)) (w qw)
           (vx (first v)) (vy (second v)) (vz (third v))
           ;; t = 2 * cross(q.xyz, v); v' = v + w*t + cross(q.xyz, t)
           (tx (* 2 (- (* y vz) (* z vy))))
           (ty (* 2 (- (* z vx) (* x vz))))
           (tz (* 2 (- (* x vy) (* y vx)))))
      (list (+ vx (* w tx) (- (* y tz) (* z ty)))
            (+ vy (* w ty) (- (* z tx) (* x tz)))
            (+ vz (* w tz) (- (* x ty) (* y tx)))))))

(defun quaternion->rpy (q)
  "Fixed-axis roll, pitch, yaw of the unit quaternion Q (x y z w)."
  (destructuring-bind (x y z w) q
    (list (atan (* 2 (+ (* w x) (* y z))) (- 1 (* 2 (+ (* x x) (* y y)))))
          (let ((s (* 2 (- (* w y) (* z x))))) (asin (max -1d0 (min 1d0 s))))
          (atan (* 2 (+ (* w z) (* x y))) (- 1 (* 2 (+ (* y y) (* z z))))))))

(defun inverse-origin (origin)
  "The inverse of the joint ORIGIN ((x y z) (qx qy qz qw))."
  (destructuring-bind (p q) origin
    (list (mapcar #'- (quaternion-inverse-rotate q p))
          (list (- (first q)) (- (second q)) (- (third q)) (fourth q)))))

(defun rerooted-source (robot)
  "The URDF text of ROBOT with its tree re-rooted at (ROOT-LINK ROBOT). Each joint between the
old root and the new one is reversed: a fixed joint gets the inverse origin; a movable joint
J becomes J (same name, limits and value, axis negated, identity origin) from the old child to
a new link J_reversed, plus a fixed joint J_reversed_offset with the inverse origin."
  (let* ((new-root (root-link robot))
         (path (loop for link = new-root then (parent (parent-joint link))
                     while (parent-joint link) collect (parent-joint link))))
    (dolist (j path)
      (unless (member (joint-type j) '(:fixed :revolute :continuous :prismatic))
        (urdf-fail "cannot re-root ~s at link ~s: joint ~s on the way is ~(~a~)"
                   (name robot) (name new-root) (name j) (joint-type j))))
    (let* ((doc (cxml:parse (source robot) (cxml-dom:make-dom-builder)))
           (root (dom:document-element doc)))
      (labels ((element (tag &rest attributes)
                 (let ((e (dom:create-element doc tag)))
                   (loop for (k v) on attributes by #'cddr do (dom:set-attribute e k v))
                   e))
               (origin-attributes (origin)
                 (list "xyz" (format nil "~{~,9f~^ ~}" (first origin))
                       "rpy" (format nil "~{~,9f~^ ~}" (quaternion->rpy (second origin)))))
               (set-origin (joint-element origin)
                 (let ((o (or (child-named joint-element "origin")
                              (dom:append-child joint-element (element "origin")))))
                   (loop for (k v) on (origin-attributes origin) by #'cddr
                         do (dom:set-attribute o k v)))))
        (dolist (joint-element (children-named root "joint"))
          (let ((j (find (attr joint-element "name") path :key #'name :test #'string=)))
            (when j
              (let ((parent-el (child-named joint-element "parent"))
                    (child-el (child-named joint-element "child"))
                    (inverse (inverse-origin (origin j))))
                (cond ((eq (joint-type j) :fixed)
                       (dom:set-attribute parent-el "link" (name (child j)))
                       (dom:set-attribute child-el "link" (name (parent j)))
                       (set-origin joint-element inverse))
                      (t
                       (let ((middle (format nil "~a_reversed" (name j))))
                         (dom:set-attribute parent-el "link" (name (child j)))
                         (dom:set-attribute child-el "link" middle)
                         (set-origin joint-element (list '(0d0 0d0 0d0) '(0d0 0d0 0d0 1d0)))
                         (let ((axis (or (child-named joint-element "axis")
                                         (dom:append-child joint-element (element "axis")))))
                           (dom:set-attribute axis "xyz" (format nil "~{~,9f~^ ~}" (mapcar #'- (axis j)))))
                         (dom:append-child root (element "link" "name" middle))
                         (let ((offset (element "joint" "name" (format nil "~a_offset" middle) "type" "fixed")))
                           (dom:append-child offset (element "parent" "link" middle))
                           (dom:append-child offset (element "child" "link" (name (parent j))))
                           (dom:append-child offset (apply #'element "origin" (origin-attributes inverse)))
                           (dom:append-child root offset))))))))))
      (dom:map-document (cxml:make-string-sink) doc))))

(defun robot-with-joint-origins (robot origins &key (source (source robot)) moved)
  "A copy of the parsed ROBOT with fresh links and joints (their geometry, axes and limits
shared) whose joints named in ORIGINS, an alist of joint name -> origin ((x y z) (qx qy qz qw),
as TEXT-ORIGIN gives it), have those origins, and whose source text is SOURCE: what PARSE-URDF
gives for ROBOT's text with those <origin> elements changed, without parsing the text again.
MOVED, a list of (joint-name xyz rpy) with the attribute texts those origins were read from
\(TEXT-ORIGIN's arguments), lets the physics shim make the copy from ROBOT's model as well
\(MOVED-JOINTS); NIL: from SOURCE."
  (dolist (entry origins)
    (unless (and (consp entry) (gethash (car entry) (joints robot)))
      (urdf-fail "ROBOT-WITH-JOINT-ORIGINS: ~s, expected (joint-name . origin) for a joint of ~s"
                 entry (name robot))))
  (let ((links (make-hash-table :test 'equal))
        (joints (make-hash-table :test 'equal)))
    (maphash (lambda (link-name l)
               (setf (gethash link-name links)
                     (make-instance 'link :name link-name :collision (collision l) :visual (visual l))))
             (links robot))
    (maphash (lambda (joint-name j)
               (let ((copy (make-instance 'joint
                                          :name joint-name :type (joint-type j)
                                          :parent (gethash (name (parent j)) links)
                                          :child (gethash (name (child j)) links)
                                          :origin (let ((new (assoc joint-name origins :test #'string=)))
                                                    (if new (cdr new) (origin j)))
                                          :axis (axis j) :limits (limits j) :mimic (mimic j))))
                 (setf (gethash joint-name joints) copy
                       (parent-joint (child copy)) copy)))
             (joints robot))
    (maphash (lambda (link-name l)
               (setf (child-joints (gethash link-name links))
                     (mapcar (lambda (j) (gethash (name j) joints)) (child-joints l))))
             (links robot))
    (make-instance 'robot :name (name robot) :links links :joints joints
                          :root-link (gethash (name (root-link robot)) links) :source source
                          :moved-joints (and moved
                                             (let ((base (moved-joints robot)))
                                               ;; moved again: from the first text, the later
                                               ;; moves of a joint last
                                               (cons (if base (car base) (source robot))
                                                     (append (cdr base) moved)))))))
