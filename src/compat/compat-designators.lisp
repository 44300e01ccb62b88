;;;; The era's designator vocabulary: location designators ((:to :see) (:to :reach) (:obj ...)
;;;; (:side ...) (:on "CounterTop") (:name "iai_kitchen_..._counter_top")), object designators
;;;; with (:at ...), the motion MOVING-JOINTS and the action LOOKING-AT, mapped onto today's
;;;; (:visible-for ...) (:reachable-for ...) (:object ...) (:arm ...) (:on <surface object>),
;;;; (:location ...), MOVING-ARM-JOINTS and LOOKING. A location designator that resolves to
;;;; nothing and has a key none of the keys listed here names that key in its
;;;; LOCATION-RESOLUTION-ERROR, with the keys that exist. The check runs only after every
;;;; generator (the library's, a test's or a user's, registered before or after this file) has
;;;; had its say, so a key some generator, costmap rule or validator handles never trips it.

(in-package :cram-plans-compat)

(defparameter *modern-location-keys*
  '(:pose :poses :location :object :target :visible-for :reachable-for :reachable-from :on :for
    :arm :urdf-name :part-of :name :type :frame
    ;; the household locations: containers, surfaces and relations to other objects
    :in :above :side :range :range-invert :level :level-invert :z-offset :context :object-count
    :attachment :attachments :orientation :threshold
    :left-of :right-of :in-front-of :behind :near :far-from)
  "The keys today's location generators and costmaps read.")

(defparameter *old-location-keys* '(:to :obj :side)
  "The era's keys this layer translates. (:side :left) or (:side :right) is the era's arm only
beside (:to ...) or (:obj ...); on its own, (side front) and the like are today's sides of a
container or a surface.")

(defparameter *era-marker-keys* '(:to :obj)
  "The keys that make a location designator one of the era's.")

(defvar *user-location-keys* '()
  "Keys added with REGISTER-LOCATION-KEY by code that handles them itself.")

(defun register-location-key (key)
  "Name KEY as a location key handled by your own generator or costmap rule, so an unresolvable
designator's error lists it among the keys that exist (a handled key never trips the unknown-key
message anyway: that message is given only when nothing resolved)."
  (check-type key keyword)
  (pushnew key *user-location-keys*)
  key)

(defun known-location-keys ()
  "The location keys this library and REGISTER-LOCATION-KEY know of."
  (remove-duplicates (append *modern-location-keys* *old-location-keys* (reverse *user-location-keys*))
                     :from-end t))

(defun unknown-location-keys (designator)
  (remove-if (lambda (k) (member k (known-location-keys)))
             (remove-duplicates (mapcar #'first (desig:properties designator)))))

(defmethod desig::no-solution-error :around ((designator desig:location-designator))
  "When nothing resolved DESIGNATOR and it has keys nobody documents, say so in the error."
  (let ((unknown (unknown-location-keys designator)))
    (if (null unknown)
        (call-next-method)
        (handler-case (call-next-method)
          (desig:designator-error (e)
            (error 'desig:location-resolution-error
                   :designator designator
                   :reason (format nil "~a~%The key~a ~{~s~^, ~} ~a unknown to the library ~
                                        (unless a generator of your own handles it); the keys ~
                                        that exist: ~{~(~s~)~^ ~}."
                                   (desig:designator-error-reason e)
                                   (if (rest unknown) "s" "") unknown
                                   (if (rest unknown) "are" "is") (known-location-keys))))))))

(defun old-surface-link (name environment)
  "The link of ENVIRONMENT the era's semantic-map NAME (e.g. \"iai_kitchen_kitchen_island_counter_top\")
means: NAME itself, else without the iai_kitchen_ prefix, with _counter_top read as _surface."
  (let* ((links (btr:link-names environment))
         (bare (if (uiop:string-prefix-p "iai_kitchen_" name) (subseq name 12) name))
         (surface (if (uiop:string-suffix-p bare "_counter_top")
                      (concatenate 'string (subseq bare 0 (- (length bare) 12)) "_surface")
                      bare)))
    (or (find name links :test #'string=)
        (find surface links :test #'string=)
        (find bare links :test #'string=)
        (error "Location designator (:name ~s): no link of ~s is called ~s or ~s. Surfaces: ~{~a~^ ~}."
               name (btr:name environment) name surface
               (remove-if-not (lambda (l) (search "surface" l)) links)))))

(defun current-robot ()
  (rob-int:current-robot-name))

(defun modern-object (designator)
  "DESIGNATOR (an object designator) with (:at X) read as (:location X)."
  (if (and (typep designator 'desig:object-designator)
           (assoc :at (desig:properties designator)))
      (desig:make-designator :object (mapcar (lambda (p) (if (eq (first p) :at) (cons :location (rest p)) p))
                                             (desig:properties designator)))
      designator))

(defun modern-location-description (designator)
  "The properties today's generators understand for the era's location DESIGNATOR, or NIL when
it has no old key. Keys it does not know pass through unchanged."
  (let ((props (desig:properties designator)))
    (let ((on (second (assoc :on props))) (name (second (assoc :name props))))
      (when (or (some (lambda (p) (member (first p) *era-marker-keys*)) props)
                (and (stringp on) name))
        (loop for (key value) in props
              append (case key
                       (:to (case value
                              (:see (list (list :visible-for (current-robot))))
                              (:reach (list (list :reachable-for (current-robot))))
                              (t (error "Location designator ~a: (:to ~s) is unknown; the era's ~
                                         values are :SEE and :REACH." designator value))))
                       ((:obj :object) (list (list :object (modern-object value))))
                       (:side (if (member value '(:left :right))
                                  (list (list :arm value))
                                  (list (list :side value))))
                       (:on (if (stringp value)
                                (let ((env (or (btr:get-environment-object)
                                               (error "Location designator ~a: (:on ~s) needs an ~
                                                       environment in the belief state." designator value))))
                                  (list (list :on (desig:make-designator
                                                   :object `((:type :counter-top)
                                                             (:urdf-name ,(old-surface-link (or name value) env))
                                                             (:part-of ,(btr:name env)))))))
                                (list (list :on value))))
                       (:name (if (stringp on) '() (list (list :name value))))
                       (t (list (list key value)))))))))

(defun compat-location-generator (designator)
  "Candidates of the era's location DESIGNATOR: the solutions of its modern equivalent."
  (let ((modern (modern-location-description designator)))
    (if modern
        (desig:designator-solutions (desig:make-designator :location modern))
        '())))

(desig:register-location-generator 1 compat-location-generator
  "The era's location vocabulary ((:to :see), (:to :reach), (:on \"CounterTop\") ...).")

;;; ---- motions and actions -----------------------------------------------------------------

(pushnew :moving-joints common-desig:*known-motion-types*)

(def-fact-group compat-motions (desig:motion-grounding)
  (<- (desig:motion-grounding ?d (common-desig::move-joints ?left ?right))
    (desig:desig-prop ?d (:type :moving-joints))
    (once (or (desig:desig-prop ?d (:left-configuration ?left)) (== ?left nil)))
    (once (or (desig:desig-prop ?d (:right-configuration ?right)) (== ?right nil)))
    (or (lisp-pred identity ?left) (lisp-pred identity ?right))))

(def-fact-group compat-process-modules (cpm:matching-process-module)
  (<- (cpm:matching-process-module ?d urdf-proj::urdf-proj-arms)
    (desig:desig-prop ?d (:type :moving-joints))))

(pp-plans::def-action-grounding :looking-at (d)
  (pp-plans:ground-action
   :looking (desig:make-designator :action (cons '(:type :looking)
                                                 (remove :type (desig:properties d) :key #'first)))))
