;;;; Action groundings of the household layer: each action designator becomes a plan function
;;;; with its properties completed by CRAM's defaults (robot locations, likely locations and
;;;; destinations from the object knowledge).

(in-package :cram-fetch-deliver-plans)

(defmacro def-fd-grounding (type (designator) &body body)
  "Ground action designators of TYPE (a keyword) through BODY's groundings (PP-PLANS' dispatch)."
  `(pp-plans::def-action-grounding ,type (,designator) ,@body))

(defun object-type-of (object)
  (let ((type (prop object :type)))
    (and type (keywordp type) type)))

(defun likely-location (object context)
  "Where OBJECT is to be searched: its own LOCATION, else the object knowledge's likely
location of its type in CONTEXT."
  (or (location-designator-or-nil (prop object :location) :location object)
      (let ((type (object-type-of object)))
        (unless type
          (fd-error "Cannot tell where to search for ~s: it has no LOCATION and no TYPE." object))
        (man-int:get-object-likely-location type (environment-name) nil context))))

(defun destination (object context)
  "Where OBJECT is to be delivered in CONTEXT, from the object knowledge."
  (let ((type (object-type-of object)))
    (unless type
      (fd-error "Cannot tell where to deliver ~s: it has no TYPE; give a TARGET." object))
    (man-int:get-object-destination type (environment-name) nil context)))

(defun arm-list-or-nil (value what designator)
  (cond ((null value) nil)
        ((keywordp value) (list value))
        ((and (listp value) (every #'keywordp value)) value)
        (t (fd-error "The ~(~a~) of ~s: expected an arm keyword or a list of them, got ~s."
                     what designator value))))

(def-fd-grounding :perceiving (d)
  (let ((object (object-designator-or-error (prop d :object) :perceiving d)))
    (list (resolved 'pp-plans:perceive :perceiving `((:object ,object))))))

(def-fd-grounding :navigating (d)
  (let ((location (location-designator-or-nil (prop d :location) :location d)))
    (unless location
      (fd-error "The navigating action ~s needs a LOCATION designator." d))
    (list (resolved 'navigate :navigating
                    `((:location ,location)
                      (:see ,(let ((see (prop d :see)))
                               (and see (object-designator-or-error see :navigating d))))
                      (:grasp ,(let ((grasp (prop d :grasp)))
                                 (and grasp (object-designator-or-error grasp :navigating d))))
                      (:place ,(prop d :place))
                      (:park-arms ,(if (eq (prop d :park-arms :unset) :unset) t
                                       (prop d :park-arms))))))))

(def-fd-grounding :turning-towards (d)
  (let ((target (location-designator-or-nil (prop d :target) :target d)))
    (unless target
      (fd-error "The turning-towards action ~s needs a TARGET location designator." d))
    (list (resolved 'turn-towards :turning-towards
                    `((:target ,target)
                      (:robot-location ,(location-designator-or-nil (prop d :robot-location)
                                                                    :robot-location d)))))))

(def-fd-grounding :searching (d)
  (let* ((object (prop d :object))
         (location (location-designator-or-nil (prop d :location) :location d))
         (context (prop d :context)))
    (when (and object (not (typep object 'desig:object-designator)))
      (fd-error "The searching action ~s: OBJECT is ~s, expected an object designator." d object))
    (unless (or object location)
      (fd-error "The searching action ~s needs an OBJECT or a LOCATION." d))
    (unless object
      ;; A location alone: search for the object it is relative to, where that object is.
      (setf object (or (location-reference-object location)
                       (fd-error "The searching action ~s: its LOCATION ~s is relative to no ~
                                  object, so there is nothing to search for." d location))
            location (or (location-designator-or-nil (prop object :location) :location object)
                         location)))
    (let ((location (or location (likely-location object context))))
      (list (resolved 'search-for-object :searching
                      `((:object ,object) (:location ,location)
                        (:robot-location ,(or (location-designator-or-nil
                                               (prop d :robot-location) :robot-location d)
                                              (searching-robot-location object location)))))))))

(def-fd-grounding :fetching (d)
  (let* ((object (object-designator-or-error (prop d :object) :fetching d))
         (arms (arm-list-or-nil (or (prop d :arms) (prop d :arm)) :arms d))
         (grasps (let ((g (or (prop d :grasps) (prop d :grasp)))) (if (keywordp g) (list g) g))))
    (list (resolved 'fetch :fetching
                    `((:object ,object) (:arms ,arms) (:grasps ,grasps)
                      (:robot-location ,(or (location-designator-or-nil
                                             (prop d :robot-location) :robot-location d)
                                            (fetching-robot-location object arms)))
                      (:look-location ,(or (location-designator-or-nil
                                            (prop d :look-location) :look-location d)
                                           (object-look-location object))))))))

(def-fd-grounding :delivering (d)
  (let* ((object (object-designator-or-error (prop d :object) :delivering d))
         (arm (let ((a (prop d :arm))) (if (listp a) (first a) a)))
         (target (or (location-designator-or-nil (prop d :target) :target d)
                     (destination object (prop d :context)))))
    (when arm (pp-plans::check-arm arm))
    (list (resolved 'deliver :delivering
                    `((:object ,object) (:arm ,arm) (:target ,target)
                      (:robot-location ,(or (location-designator-or-nil
                                             (prop d :robot-location) :robot-location d)
                                            (delivering-robot-location target arm))))))))

(def-fd-grounding :transporting (d)
  (let* ((object (object-designator-or-error (prop d :object) :transporting d))
         (context (prop d :context))
         (arms (arm-list-or-nil (prop d :arms) :arms d))
         (grasps (prop d :grasps)))
    (when (and grasps (not (and (listp grasps) (every #'keywordp grasps))))
      (fd-error "The GRASPS of ~s: expected a list of grasp keywords, got ~s." d grasps))
    (list (resolved 'transport :transporting
                    `((:object ,object) (:context ,context) (:arms ,arms) (:grasps ,grasps)
                      (:search-location ,(likely-location object context))
                      (:delivery-location ,(or (location-designator-or-nil
                                                (prop d :target) :target d)
                                               (destination object context)))
                      (:search-robot-location ,(prop d :search-robot-location))
                      (:fetch-robot-location ,(prop d :fetch-robot-location))
                      (:deliver-robot-location ,(prop d :deliver-robot-location)))))))
