;;;; Publishing the belief state: TF messages on /tf, a MarkerArray on
;;;; /visualization_marker_array, on demand and from a background thread at a fixed rate.

(in-package :roslisp-utilities)

(defvar *tf-topic* "/tf" "The topic the belief state's transforms go to (tf2_msgs/TFMessage).")

(defvar *marker-topic* "/visualization_marker_array"
  "The topic the belief state's object markers go to (visualization_msgs/MarkerArray).")

(defvar *publications* '()
  "Alist topic → roslisp publication advertised by this node (reset when a node starts or stops).")

(defvar *published-marker-names* '()
  "Names of the objects whose markers were last published (so removed objects get deleted).")

(defvar *publish-lock* (bt:make-recursive-lock "belief state publishing"))

(defun reset-publications ()
  (bt:with-recursive-lock-held (*publish-lock*)
    (setf *publications* '() *published-marker-names* '())))

(defun publication (topic type)
  "The publication of TOPIC (advertised as TYPE on first use in this node)."
  (bt:with-recursive-lock-held (*publish-lock*)
    (or (cdr (assoc topic *publications* :test #'string=))
        (let ((pub (roslisp:advertise topic type)))
          (push (cons topic pub) *publications*)
          pub))))

;;; ---- messages ----------------------------------------------------------------------------------

(defun to-d (x) (coerce x 'double-float))
(defun to-f (x) (coerce x 'single-float))

(defun header (frame stamp)
  (make-instance 'std_msgs-msg:Header :frame_id frame :stamp stamp))

(defun quaternion-msg (q)
  (make-instance 'geometry_msgs-msg:Quaternion
                 :x (to-d (cl-transforms:x q)) :y (to-d (cl-transforms:y q))
                 :z (to-d (cl-transforms:z q)) :w (to-d (cl-transforms:w q))))

(defun transform-msg (parent child transform stamp)
  "A geometry_msgs/TransformStamped of CHILD in PARENT."
  (let ((tr (cl-transforms:translation transform)))
    (make-instance 'geometry_msgs-msg:TransformStamped
                   :header (header parent stamp)
                   :child_frame_id child
                   :transform (make-instance
                               'geometry_msgs-msg:Transform
                               :translation (make-instance 'geometry_msgs-msg:Vector3
                                                           :x (to-d (cl-transforms:x tr))
                                                           :y (to-d (cl-transforms:y tr))
                                                           :z (to-d (cl-transforms:z tr)))
                               :rotation (quaternion-msg (cl-transforms:rotation transform))))))

(defun marker-code (key)
  (roslisp-msg-protocol:symbol-code 'visualization_msgs-msg:Marker key))

(defun marker-msg (marker frame stamp)
  "A visualization_msgs/Marker (action ADD) from a plist of BELIEF-STATE-MARKERS."
  (destructuring-bind (&key id type pose scale color mesh-resource &allow-other-keys) marker
    (let ((o (cl-transforms:origin pose)))
      (make-instance 'visualization_msgs-msg:Marker
                     :header (header frame stamp)
                     :ns *marker-namespace* :id id
                     :type (marker-code type) :action (marker-code :add)
                     :pose (make-instance 'geometry_msgs-msg:Pose
                                          :position (make-instance 'geometry_msgs-msg:Point
                                                                   :x (to-d (cl-transforms:x o))
                                                                   :y (to-d (cl-transforms:y o))
                                                                   :z (to-d (cl-transforms:z o)))
                                          :orientation (quaternion-msg (cl-transforms:orientation pose)))
                     :scale (make-instance 'geometry_msgs-msg:Vector3
                                           :x (to-d (first scale)) :y (to-d (second scale)) :z (to-d (third scale)))
                     :color (make-instance 'std_msgs-msg:ColorRGBA
                                           :r (to-f (first color)) :g (to-f (second color))
                                           :b (to-f (third color)) :a (to-f (fourth color)))
                     :mesh_resource mesh-resource
                     :mesh_use_embedded_materials nil))))

(defun delete-marker-msg (name frame stamp)
  (make-instance 'visualization_msgs-msg:Marker
                 :header (header frame stamp) :ns *marker-namespace* :id (marker-id name)
                 :action (marker-code :delete)))

;;; ---- publishing --------------------------------------------------------------------------------

(defun %publish-belief-state (world markers)
  "PUBLISH-BELIEF-STATE with roslisp loaded and a node running."
  (let* ((stamp (roslisp:ros-time))
         (edges (belief-state-transforms :world world))
         (marker-list (and markers (belief-state-markers :world world))))
    (bt:with-recursive-lock-held (*publish-lock*)
      (roslisp:publish (publication *tf-topic* "tf2_msgs/TFMessage")
                       (make-instance 'tf2_msgs-msg:TFMessage
                                      :transforms (map 'vector (lambda (e) (apply #'transform-msg (append e (list stamp))))
                                                       edges)))
      (when markers
        (let* ((names (mapcar (lambda (m) (getf m :name)) marker-list))
               (gone (set-difference *published-marker-names* names)))
          (roslisp:publish (publication *marker-topic* "visualization_msgs/MarkerArray")
                           (make-instance 'visualization_msgs-msg:MarkerArray
                                          :markers (concatenate 'vector
                                                                (mapcar (lambda (n) (delete-marker-msg n *tf-fixed-frame* stamp)) gone)
                                                                (mapcar (lambda (m) (marker-msg m *tf-fixed-frame* stamp)) marker-list))))
          (setf *published-marker-names* names))))
    (values (length edges) (length marker-list))))

;;; ---- the background thread ---------------------------------------------------------------------

(defvar *publisher-thread* nil "The thread of START-BELIEF-STATE-PUBLISHER, or NIL.")
(defvar *publisher-stop* nil "Set to true to make the publisher thread end.")

(defun %belief-state-publisher-running-p ()
  "True while the background belief-state publisher thread runs."
  (and *publisher-thread* (bt:thread-alive-p *publisher-thread*) t))

(defun publisher-loop (rate)
  (let ((period (/ 1d0 rate)) (last-error nil))
    (loop until (or *publisher-stop* (not (ros-running-p)))
          do (let ((start (get-internal-real-time)))
               (handler-case (progn (publish-belief-state :world btr:*current-bullet-world*)
                                    (setf last-error nil))
                 (error (e)
                   (let ((text (princ-to-string e)))
                     (unless (equal text last-error)
                       (ros-log :warn "Publishing the belief state failed: ~a" text)
                       (setf last-error text)))))
               (let ((left (- period (/ (- (get-internal-real-time) start)
                                        internal-time-units-per-second))))
                 ;; sleep in short steps so a stop request is seen quickly
                 (loop while (and (> left 0) (not *publisher-stop*))
                       do (sleep (min left 0.05d0)) (decf left 0.05d0)))))))

(defun %start-belief-state-publisher (rate)
  "START-BELIEF-STATE-PUBLISHER with roslisp loaded and a node running."
  (%stop-belief-state-publisher)
  (setf *publisher-stop* nil
        *publisher-thread* (bt:make-thread (lambda () (publisher-loop rate))
                                           :name "belief state publisher"))
  *publisher-thread*)

(defun %stop-belief-state-publisher ()
  "Stop the background publisher thread and wait for it to end; true when one was running."
  (let ((thread *publisher-thread*))
    (when thread
      (setf *publisher-stop* t)
      (unless (eq thread (bt:current-thread))
        (sb-thread:join-thread thread :timeout 5 :default nil)
        (when (bt:thread-alive-p thread) (ignore-errors (bt:destroy-thread thread))))
      (setf *publisher-thread* nil)
      t)))
